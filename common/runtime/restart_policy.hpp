#pragma once

#include <map>
#include <optional>

#include "common/scenario/fault_plan.hpp"

namespace qswarm {

// When an agent whose life ended comes back: the one rule the launcher (real processes) and the
// in-process swarm (AgentLoops on a manual clock) both follow. Only a planned kill restarts an
// agent, and only as often as the plan restarts it: its n-th new life joins the swarm's clock at
// the plan's n-th restart time and recovers the flows it owned. Anything else that ends a life (a
// crash, a kill from outside, a clean exit) is final.
class RestartPolicy {
 public:
  explicit RestartPolicy(FaultPlan plan) : plan_(std::move(plan)) {}

  // Whether an end by SIGKILL is the agent's next planned kill: it marked that many planned kills
  // before dying (`marked`), more than have been seen, and the plan has one left. A SIGKILL sent
  // from outside, even while planned kills are left, is not planned.
  bool is_planned_kill(AgentId id, int marked) const;
  // Counts a planned kill and returns the join time of the agent's next life if the plan restarts
  // it (nothing: it stays dead).
  std::optional<double> after_planned_kill(AgentId id);
  // Lives started after the first (restarts so far).
  int restarts(AgentId id) const;

 private:
  FaultPlan plan_;
  std::map<AgentId, int> kills_seen_;
  std::map<AgentId, int> restarts_;
};

}  // namespace qswarm
