#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "common/clock/clock.hpp"
#include "common/core/airframe.hpp"
#include "common/core/avoidance.hpp"
#include "common/core/plant.hpp"
#include "common/core/update_law.hpp"
#include "common/runtime/link_faults.hpp"
#include "common/scenario/run_config.hpp"
#include "common/transport/neighbor_bus.hpp"

namespace qswarm {

// How this life of the agent starts (beyond what every agent of the run shares).
struct AgentStart {
  std::int64_t incarnation = 0;  // this life's identity: a restarted agent has a newer one
  std::uint64_t run_id = 0;      // carried in every sample
  // The law starts when this many peers are running (so the first tick sees the whole initial
  // graph), or after start_grace_s when some never come (late join, dead peer).
  std::size_t expected_peers = 0;
  double start_grace_s = 1.0;
  // A late joiner or restarted agent starts on the swarm's clock, not at 0.
  double start_time_s = 0.0;
  // Restarted: recover the flows it owned from the neighbours' copies before its first tick.
  bool recover_flows = false;
  // Every how many samples one also goes to the recorder (RunPlan::record_every).
  std::uint32_t record_every = 1;
  // Which one of every record_every ticks it records: the same for every agent, or by its id
  // (RunPlan::spread_records).
  bool spread_records = false;
  // Whether the samples its neighbours hear carry its links. Only a place filter reads them
  // (delivery REACH: a bond lets a sample through); the recorder's samples always carry its
  // links and initial links (graph.csv), and no neighbour reads the initial ones. Without them a
  // sample's size follows the edges still settling, not twice the degree more.
  bool links_to_neighbours = true;
  // Where it flies (StateMessage::host), told the recorder; empty in the in-process swarm.
  std::string host;
};

// One agent: who it is and where it starts (its spec), what every agent of the run flies with (the
// run's agent config), and how this life starts.
struct AgentParams {
  AgentSpec spec;
  AgentConfig config;
  AgentStart start;
};

// What happened in a step that the process should log (the runtime itself does no I/O).
struct AgentEvent {
  enum Kind { kNeighborHeard, kNeighborLost } kind;
  AgentId peer;
  double t_s;
};

// One agent: its agreement law, its plant (common/plants/: the paper's point agent or quadcopter)
// and, between them, the reference with collision avoidance, stepped in simulated time. No I/O, and
// no clock but the one it reads the wall time its samples carry from: AgentLoop paces it (in real
// time in swarm-agent, on a manual clock in the in-process swarm).
class AgentRuntime {
 public:
  AgentRuntime(AgentParams p, NeighborBus& bus);

  // One physics step of 1/physics_hz; every physics_hz/consensus_hz steps also a consensus tick
  // (read neighbours, update the law, publish). Returns events for logging.
  std::vector<AgentEvent> step();
  // Publish the current state (the process calls this while waiting for peers, with
  // Phase::kWaiting). The recorder gets every record_every-th sample, the goodbye, and any sample
  // published with `record` (a barrier announcement when the last record is a record period old:
  // announcements there are slower than ticks). With record_every above 1 the first running
  // sample is not recorded. Returns whether the recorder got this one.
  bool publish(Phase phase, bool record = false);

  // A late or restarted agent starts on the swarm's clock: set before the first step.
  void set_start_time(double t_s);
  // An agent that found the swarm long in flight (LifecycleStep::late): on the swarm's clock, no
  // wait for the initial graph, the flows it held asked back. Before the first step.
  void join_running(double t_s);

  double time_s() const {
    return p_.start.start_time_s + static_cast<double>(steps_) / p_.config.physics_hz;
  }
  const Plant& plant() const { return *plant_; }
  Vec3 consensus() const { return law_->state(); }
  // Whether this agent heard a new sample of the peer since its last tick or the one before (the
  // view its law then gets is current: NeighborView::current).
  bool hears(AgentId peer) const;
  Vec3 position() const { return plant_->position(); }
  Vec3 velocity() const { return plant_->velocity(); }
  const UpdateLaw& law() const { return *law_; }
  const AgentParams& params() const { return p_; }
  std::uint64_t published() const { return seq_; }
  int steps_per_tick() const { return steps_per_tick_; }

  // Stamps for publication: the loop injects its clock and counters. A sample carries the wall
  // time at which it is handed to the transport (as DDS's source timestamp would), so that its age
  // where it arrives is its time in transit, not also the tick that computed it (none: 0).
  void set_wall_clock(const Clock* clock) { wall_clock_ = clock; }
  void set_fault_counters(const FaultCounters& c) { faults_ = c; }
  int recovered_flows() const { return law_->recovered_count(); }
  // Simulated time of the law's first tick (-1 before): the start barrier's first tick, or up to
  // start_grace_s later if some expected peer never ran.
  double law_start_s() const { return law_start_s_; }
  void set_counters(std::uint64_t received, std::uint64_t dropped, std::uint64_t overruns) {
    received_ = received;
    dropped_ = dropped;
    overruns_ = overruns;
  }
  // Stranger ids its transport dropped (reported in its samples, at most kMaxStrangers).
  void set_strangers(const std::set<AgentId>& ids);
  // Agents its transport found forged (reported in its samples, at most kMaxSuspects).
  void set_suspects(const std::map<AgentId, std::uint8_t>& suspects);
  // The start barrier's bitsets its waiting and ready announcements carry (AgentLifecycle).
  void set_barrier(const std::vector<std::uint8_t>& known, const std::vector<std::uint8_t>& ready,
                   double ready_at_s) {
    barrier_known_ = known;
    barrier_ready_ = ready;
    barrier_ready_at_s_ = ready_at_s;
  }

 private:
  void consensus_tick(std::vector<AgentEvent>& events);
  // The wall time a sample handed over now carries (0 without a clock).
  std::int64_t wall_now_ns() const { return wall_clock_ ? wall_clock_->wall_ns() : 0; }
  void physics(double dt);
  // Its slot about its consensus estimate: where the law puts it.
  Vec3 goal() const { return law_->state() + p_.spec.offset_W; }

  AgentParams p_;
  NeighborBus& bus_;
  std::unique_ptr<UpdateLaw> law_;
  std::set<AgentId> listen_to_;  // fixed topology: only these peers
  int steps_per_tick_ = 10;
  std::uint64_t steps_ = 0;
  std::uint64_t seq_ = 0;
  bool published_running_ = false;
  bool started_ = false;
  double law_start_s_ = -1.0;
  const PlantSpec& plant_spec_;
  std::unique_ptr<Plant> plant_;
  ReferenceGenerator reference_;     // the rate-limited reference the plant tracks
  std::vector<Obstacle> obstacles_;  // scratch, reused every physics step
  // The law's views of the neighbours, refilled at every consensus tick into the storage its
  // elements already have (a tick then allocates nothing once the lists have grown).
  std::vector<NeighborView> views_;
  // Every agent heard, in any phase: the law reads its running ones, collision avoidance all but
  // stopping ones. A peer is silent when no new sample came for the neighbour timeout.
  struct Peer {
    std::uint64_t seq = 0;
    std::int64_t incarnation = 0;
    double last_new_s = 0.0;        // this agent's time when its newest sample arrived
    Phase phase = Phase::kWaiting;  // of its newest sample
    Vec3 p_W = Vec3::Zero(), v_W = Vec3::Zero();
    double at_s = 0.0;  // the swarm time p_W is for
  };
  // Heard anew within two ticks, or a quarter of the neighbour timeout if that is longer (samples
  // run late on a loaded host; a link must still form).
  bool current(const Peer& p, double t) const;
  std::map<AgentId, Peer> peers_;
  std::set<AgentId> live_;
  std::vector<std::pair<AgentId, double>> initial_links_;  // links at the law's first tick
  const Clock* wall_clock_ = nullptr;
  std::uint64_t received_ = 0, dropped_ = 0, overruns_ = 0;
  std::vector<AgentId> strangers_;
  std::vector<Suspect> suspects_;
  std::vector<std::uint8_t> barrier_known_, barrier_ready_;
  double barrier_ready_at_s_ = 0.0;
  FaultCounters faults_;
};

}  // namespace qswarm
