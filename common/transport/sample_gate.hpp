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
  enum class Verdict { kAccepted, kInvalid, kStale };
  struct Result {
    Verdict verdict = Verdict::kAccepted;
    std::string why;  // for kInvalid
    bool first_from =
        false;  // kInvalid: the first refusal from this agent (log it; count the rest)
  };
  // `why` is check_message(m), computed by the caller outside its lock.
  Result admit(const StateMessage& m, const std::string& why);
  std::vector<StateMessage> latest(AgentId self) const;
  BusCounters& counters() { return counters_; }
  const BusCounters& counters() const { return counters_; }

 private:
  std::map<AgentId, StateMessage> latest_;
  std::set<AgentId> warned_;
  BusCounters counters_;
};

}  // namespace qswarm
