#pragma once

#include <vector>

#include "common/record/presence.hpp"
#include "common/runtime/fault_plan.hpp"
#include "proto/records.pb.h"

namespace qswarm {

// The convergence judgement: the swarm has converged once, for hold_s of simulated time, every
// agent the plan has brought back (a due restart or late join) is running, the last planned fault
// is over, and the running agents' consensus states and positions agree within tolerance. An
// unplanned departure (a crash, an outside kill) does not stop the others from converging. Pure.
class ConvergenceJudge {
 public:
  ConvergenceJudge(double tolerance_m, double hold_s, FaultPlan plan);
  // Feed each graph snapshot; returns true the first time the swarm counts as converged.
  bool update(double t_s, const records::GraphSnapshot& g, const Presence& presence);
  bool converged() const { return converged_; }
  // Start of the hold that ended in convergence (-1 before).
  double converged_at_s() const { return converged_at_s_; }

 private:
  bool everyone_due_is_back(double t_s, const Presence& presence) const;
  double tolerance_m_, hold_s_;
  FaultPlan plan_;
  double hold_start_s_ = -1.0;
  bool converged_ = false;
  double converged_at_s_ = -1.0;
};

}  // namespace qswarm
