#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "common/transport/neighbor_bus.hpp"

namespace qswarm {

// Who wrote a sample, as the transport knows it (DDS: the writer's GUID). All zero: not known (the
// in-memory bus), and every sample of an agent counts as one writer's.
struct WriterId {
  std::array<std::uint8_t, 16> bytes{};
  bool known() const;
  bool operator==(const WriterId&) const = default;
  std::string str() const;  // hex, for logs
  std::uint64_t hash() const;
};

// The law a run flies, as its samples must show it: a sample of another law, or whose payload is
// longer than the law's bound, is invalid (tag 0: no check).
struct ExpectedLaw {
  std::uint32_t tag = 0;  // law_tag of its name
  std::size_t payload_max = kMaxLawPayload;
};
// What the registered law `law_name` sends (find_law: throws std::invalid_argument if none).
ExpectedLaw expected_law(const std::string& law_name);

// What every transport does with an incoming sample, in one place: check it (check_message),
// refuse it if it is not newer than the one held from that agent, keep the newest per agent, and
// count. Not thread-safe: the transport holds its own lock around it.
//
// Without DDS-Security anyone on the network can publish an agent's key, so the gate also watches
// who writes each agent (WriterId) and names what it cannot prevent (SuspectKind, reported in
// the agent's samples and in the record):
// - The first writer heard for an agent owns it; another writer's samples are refused while the
//   owner speaks. Two writers whose samples interleave (one heard again after the other spoke,
//   kReturns times) are two at once: an impersonator, or a relay of the real one. A restart never
//   interleaves (the old process is gone).
// - Ownership passes to another writer after kTakeover of its samples in a row with none from the
//   owner: a restarted agent is heard after that many, and an agent whose forger stopped is heard
//   again, whatever sequence numbers or start times the forger used. Order (is_newer) is judged
//   within one writer's samples.
// - A sequence number far beyond what the agent could have sent since the held sample (a forged
//   "newer" one) is refused and named. When the owner's own numbers are that far ahead of another
//   writer's in the same life, and beyond what that life could have sent since it began, the
//   owner is the one forging them (a relay heard first): the other writer takes the agent at once.
//   An incarnation from the future is refused and named.
class SampleGate {
 public:
  enum class Verdict { kAccepted, kInvalid, kStale, kForeign, kContested };
  // run_id: the run this endpoint belongs to; a sample of another run is foreign (0: no check).
  explicit SampleGate(std::uint64_t run_id = 0, ExpectedLaw law = {})
      : run_id_(run_id), law_(law) {}
  struct Result {
    Verdict verdict = Verdict::kAccepted;
    std::string why;  // for kInvalid and kContested
    // kInvalid: the first refusal from this agent (log it; count the rest); kForeign: the
    // first sample of that run.
    bool first_from = false;
    // SuspectKind bits noticed for this agent for the first time (log them once).
    std::uint8_t noticed = 0;
    // Another writer took the agent over (a restart, or the owner went silent while a forger
    // spoke, or the real agent is heard again after its forger stopped).
    bool new_owner = false;
  };
  // `why` is check_message(m), computed by the caller outside its lock. With the receiver's wall
  // clock (now_wall_ns > 0), an incarnation (the sender's start time) more than a minute in the
  // future is refused, and so is a sequence jump. `writer`: who wrote it (not known: all zero).
  Result admit(const StateMessage& m, const std::string& why, std::int64_t now_wall_ns = 0,
               const WriterId& writer = {});
  // Names a suspicion found outside the gate (a secure transport's refusal); returns whether it
  // is new for that agent.
  bool notice(AgentId id, std::uint8_t kinds);
  // The newest accepted message of every agent other than `self`, in id order, each passed to
  // `visit` (NeighborBus::for_each_latest serves it).
  void for_each_latest(AgentId self, const std::function<void(const StateMessage&)>& visit) const;
  BusCounters& counters() { return counters_; }
  const BusCounters& counters() const { return counters_; }
  // Other runs heard on this endpoint's domain (their run ids).
  const std::set<std::uint64_t>& foreign_runs() const { return foreign_runs_; }
  // Agents whose samples were found forged, with SuspectKind bits.
  const std::map<AgentId, std::uint8_t>& suspects() const { return suspects_; }

  // Samples of another writer in a row that take an agent over from a silent owner.
  static constexpr int kTakeover = 3;
  // A sample more than this many sequence numbers beyond the held one, plus kMaxRatePerS per
  // second since it arrived, is a jump. Nothing publishes faster than consensus_hz (at most 1 kHz)
  // times the time scale (at most 100), or than the start barrier's announcements.
  static constexpr std::uint64_t kJumpSlack = 10'000;
  static constexpr double kMaxRatePerS = 1e5;

 private:
  struct Agent {
    StateMessage held;
    std::int64_t held_at_ns = 0;  // when it was accepted (receiver's clock; 0: unknown)
    WriterId owner;
    WriterId contender;  // the last other writer heard
    int contender_run = 0;
    // The writers heard lately (by hash) and at which of this agent's samples, to tell a writer
    // heard again after another spoke; how often that happened.
    struct Seen {
      std::uint64_t writer = 0;
      std::uint64_t at = 0;
    };
    std::array<Seen, 4> seen{};
    std::uint64_t samples = 0;
    std::uint64_t last_writer = 0;
    int returns = 0;
  };
  static constexpr int kReturns = 3;
  // A writer is heard "again" only within this many of the agent's samples since its last one: a
  // long-gone life's late sample is not a second writer.
  static constexpr std::uint64_t kRecentSamples = 256;
  // Whether `samples` sequence numbers are more than anything could send in `since_s` seconds.
  static bool more_than_sent(std::uint64_t samples, double since_s);
  // How far `a` is ahead of `b` in the same life beyond what the agent could have sent in
  // `since_s` (> 0: a jump).
  static bool far_ahead(const StateMessage& a, const StateMessage& b, double since_s);
  bool jumps(const StateMessage& m, const Agent& a, std::int64_t now_wall_ns) const;
  bool behind(const StateMessage& m, const Agent& a, std::int64_t now_wall_ns) const;
  // A sequence number beyond what its life (since m.incarnation) could have reached.
  static bool implausible(const StateMessage& m, std::int64_t now_wall_ns);
  bool interleaved(Agent& a, const WriterId& w);
  std::uint8_t notice_bits(AgentId id, std::uint8_t kinds);
  // Counts an accepted sample, and its age on arrival where both clocks are known.
  void count_accepted(const StateMessage& m, std::int64_t now_wall_ns);

  std::map<AgentId, Agent> agents_;
  std::set<AgentId> warned_;
  BusCounters counters_;
  std::uint64_t run_id_;
  ExpectedLaw law_;
  std::set<std::uint64_t> foreign_runs_;
  std::map<AgentId, std::uint8_t> suspects_;
};

}  // namespace qswarm
