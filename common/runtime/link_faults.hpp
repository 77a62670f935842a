#pragma once

#include <cstdint>
#include <map>
#include <random>
#include <vector>

#include "common/scenario/fault_plan.hpp"
#include "common/transport/state_message.hpp"

namespace qswarm {

// Decides, for every message arriving at agent `self`, whether the plan drops or delays it. One
// random stream per directed link, seeded from (seed, from, self): a run replays. Pure.
class LinkFaults {
 public:
  LinkFaults(FaultPlan plan, AgentId self, std::uint64_t seed);
  struct Verdict {
    bool drop = false;
    double delay_s = 0.0;
  };
  Verdict on_receive(AgentId from, double t_s);
  const FaultCounters& counters() const { return counters_; }
  // The plan injects nothing on any link (no cut, partition, loss, burst or delay).
  bool none() const;
  bool cut_now(AgentId from, double t_s) const;

 private:
  struct Link {
    std::mt19937_64 rng;
    std::vector<bool> bad;  // Gilbert-Elliott state per burst entry
  };
  Link& link(AgentId from);
  FaultPlan plan_;
  AgentId self_;
  std::uint64_t seed_;
  std::map<AgentId, Link> links_;
  FaultCounters counters_;
  std::vector<double> draws_;
};

}  // namespace qswarm
