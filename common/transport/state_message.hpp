#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "common/core/agent.hpp"
#include "common/core/dynamics.hpp"
#include "common/core/update_law.hpp"

namespace qswarm {

// Faults injected in one agent's receive path (this incarnation's counts, which only grow): carried
// in its samples, summed in the record.
struct FaultCounters {
  std::uint64_t loss = 0, burst = 0, cut = 0, partition = 0, delayed = 0;
  std::uint64_t dropped() const { return loss + burst + cut + partition; }
  FaultCounters& operator+=(const FaultCounters& o) {
    loss += o.loss;
    burst += o.burst;
    cut += o.cut;
    partition += o.partition;
    delayed += o.delayed;
    return *this;
  }
  bool operator==(const FaultCounters&) const = default;
};

// An agent's phase as its samples carry it. Start barrier: an agent is kWaiting until it has heard
// every expected peer, then kReady; it runs once every expected peer is kReady or kRunning, so a
// swarm starts within one waiting-publish period.
enum class Phase : std::uint8_t { kWaiting = 0, kRunning = 1, kStopping = 2, kReady = 3 };

// The start barrier's swarm-wide flood: bit k of a bitset is the run's k-th agent (ids ascending),
// so kMaxSwarmAgents agents need this many bytes (the wire's bound).
inline constexpr std::size_t kMaxBarrierBytes = (kMaxSwarmAgents + 7) / 8;

// How many stranger ids a sample reports (the wire's bound).
inline constexpr std::size_t kMaxStrangers = 16;

// What a receiver found forged in one agent's samples (bits; SampleGate says how it decides).
// Carried in samples, so that the recorder, which does not hear the agents' stream, names them.
enum SuspectKind : std::uint8_t {
  kTwoWriters = 1,         // two writers published the agent's samples at once
  kSequenceJump = 2,       // a sequence number beyond what the agent could have sent (refused)
  kFutureIncarnation = 4,  // a start time more than a minute ahead (refused)
  // DDS-Security: a writer whose certificate binds it to another agent published them (refused).
  kBoundElsewhere = 8,
};
inline constexpr std::uint8_t kAllSuspectKinds = 15;
struct Suspect {
  AgentId id = 0;
  std::uint8_t kinds = 0;  // SuspectKind bits
  bool operator==(const Suspect&) const = default;
};
// How many suspects a sample reports (the wire's bound).
inline constexpr std::size_t kMaxSuspects = 16;
// The longest host a sample names (the wire's bound).
inline constexpr std::size_t kMaxHostBytes = 64;
// The name of one kind in the record ("two_writers") and what it means for people.
const char* suspect_name(SuspectKind k);
const char* suspect_text(SuspectKind k);

// One agent's published state: the consensus part its neighbours' laws read, plus the physical
// part the supervisor records. The DDS type in idl/ mirrors this.
struct StateMessage {
  NeighborView view;  // id, consensus state, total weight, owned flows
  std::uint64_t seq = 0;
  double stamp_s = 0.0;                 // sender's run time
  PoseKind mode = PoseKind::kPosition;  // whether q_WB and rotors_radps say anything
  Vec3 p_W = Vec3::Zero();
  Vec3 v_W = Vec3::Zero();
  Eigen::Quaterniond q_WB = Eigen::Quaterniond::Identity();
  RotorSpeeds rotors_radps = RotorSpeeds::Zero();
  std::vector<std::pair<AgentId, double>> links;  // edges the sender holds, with weights
  // The links its law started with: the swarm's initial graph survives a recorder that matched
  // this agent's writer a few ticks late (discovery is per side; samples are best-effort).
  std::vector<std::pair<AgentId, double>> initial_links;
  std::int64_t wall_ns = 0;      // sender's CLOCK_REALTIME at publication
  std::int64_t incarnation = 0;  // sender's start time: a restarted agent has a newer one
  std::uint64_t run_id = 0;      // the run the sender belongs to (RunConfig::run_id)
  Phase phase = Phase::kWaiting;
  std::uint64_t received = 0;  // samples the sender accepted
  std::uint64_t dropped = 0;   // samples the sender rejected
  std::uint64_t overruns = 0;  // the sender's late ticks
  std::uint64_t trimmed = 0;   // neighbour values the sender's law trimmed so far (W-MSR)
  FaultCounters faults;        // injected in the sender's receive path (this incarnation)
  // Ids outside the run whose samples the sender's transport dropped (the first kMaxStrangers):
  // the recorder, which does not hear the agents' stream, names each stranger from these.
  std::vector<AgentId> strangers;
  // Agents whose samples the sender's transport found forged (the first kMaxSuspects).
  std::vector<Suspect> suspects;
  // At the start barrier only (waiting or ready; empty otherwise), bitsets over the run's agents
  // (kMaxBarrierBytes): the agents the sender knows start with it (its start peers and theirs,
  // transitively), and those it knows are ready. AgentLifecycle says how the start uses them.
  std::vector<std::uint8_t> barrier_known, barrier_ready;
  // Where the sender flies, "NAME/ADDRESS" (its host name, the address its DDS traffic uses): in
  // the recorder's samples only (empty in its neighbours'), so the record says which host each
  // agent flew on, a restart on another host included. Printable ASCII without ',' or '"'.
  std::string host;
  // With them: the latest instant, on the host's shared time line, at which an agent in
  // barrier_ready turned ready.
  double barrier_ready_at_s = 0.0;
};

// Whether the sender of `m` is bonded with agent `id`: names it among its links, its edges'
// entries (flows it owns, copies it holds: an exchange still to settle) or the peers it asks
// after a restart. Such a sample must reach that agent wherever it is (Interest::hears).
bool mentions(const StateMessage& m, AgentId id);

// Empty if a received message is usable, else why not. Anything non-finite or absurd is refused.
std::string check_message(const StateMessage& m);

// Whether `m` supersedes `held` from the same agent: a newer life (restart), or a larger sequence
// number in the same life. Older or repeated samples (reordering, duplicates) are stale.
inline bool is_newer(const StateMessage& m, const StateMessage& held) {
  return m.incarnation > held.incarnation ||
         (m.incarnation == held.incarnation && m.seq > held.seq);
}

}  // namespace qswarm
