#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "common/transport/neighbor_bus.hpp"

namespace qswarm {

// What every transport does with an incoming sample, in one place: check it (check_message),
// refuse it if it is not newer than the one held from that agent, keep the newest per agent, and
// count. Not thread-safe: the transport holds its own lock around it.
class SampleGate {
 public:
  enum class Verdict { kAccepted, kInvalid, kStale, kForeign };
  // run_id: the run this endpoint belongs to; a sample of another run is foreign (0: no check).
  explicit SampleGate(std::uint64_t run_id = 0) : run_id_(run_id) {}
  struct Result {
    Verdict verdict = Verdict::kAccepted;
    std::string why;  // for kInvalid
    // kInvalid: the first refusal from this agent (log it; count the rest); kForeign: the
    // first sample of that run.
    bool first_from = false;
  };
  // `why` is check_message(m), computed by the caller outside its lock. With the receiver's wall
  // clock (now_wall_ns > 0), an incarnation (the sender's start time) more than a minute in the
  // future is refused: it would lock the real agent out as "stale" for the rest of the run.
  Result admit(const StateMessage& m, const std::string& why, std::int64_t now_wall_ns = 0);
  std::vector<StateMessage> latest(AgentId self) const;
  BusCounters& counters() { return counters_; }
  const BusCounters& counters() const { return counters_; }
  // Other runs heard on this endpoint's domain (their run ids).
  const std::set<std::uint64_t>& foreign_runs() const { return foreign_runs_; }

 private:
  std::map<AgentId, StateMessage> latest_;
  std::set<AgentId> warned_;
  BusCounters counters_;
  std::uint64_t run_id_;
  std::set<std::uint64_t> foreign_runs_;
};

}  // namespace qswarm
