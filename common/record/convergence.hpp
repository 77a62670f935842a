#pragma once

#include <vector>

#include "common/record/presence.hpp"
#include "common/scenario/fault_plan.hpp"
#include "proto/records.pb.h"

namespace qswarm {

// The convergence judgement. The running agents agree once, for hold_s of simulated time, their
// consensus states and positions lie within tolerance and the last planned fault is over. The
// swarm has converged only if, in addition, every agent the run expects alive (the fault plan's
// due_alive) is running: an agent that crashed, was killed from outside, is stopped or never came
// is missing, and a swarm that agreed without it has not converged. When the others have agreed
// without a missing agent for hold_s plus the neighbour timeout, the judgement says so (the run
// can end, saying who was missing). Under a law that keeps the initial average exactly
// (edge-flow), agreeing farther than max_drift_m from it is no convergence either: nothing in the
// law moves the mean, so something outside it did (a participant publishing forged states or
// flows). Pure.
class ConvergenceJudge {
 public:
  enum class Verdict { kNone, kConverged, kAgreedWithoutSome, kAgreedElsewhere };
  // max_drift_m < 0: the law does not keep the average (laplacian, w-msr), no such check.
  ConvergenceJudge(double tolerance_m, double hold_s, double timeout_s, double max_drift_m,
                   FaultPlan plan);
  // Feed each graph snapshot; returns a verdict the first time one is reached.
  Verdict update(double t_s, const records::GraphSnapshot& g, const Presence& presence);
  bool converged() const { return converged_; }
  bool agreed_without_some() const { return !missing_.empty(); }
  // The agents agreed, but max_drift_m or more away from the initial average: how far (-1: no).
  double agreed_elsewhere_m() const { return elsewhere_m_; }
  // The agents the run expected that were not running when the others agreed.
  const std::vector<AgentId>& missing() const { return missing_; }
  // Start of the hold that ended in a verdict (-1 before).
  double converged_at_s() const { return converged_at_s_; }

 private:
  std::vector<AgentId> missing_now(double t_s, const Presence& presence) const;
  double tolerance_m_, hold_s_, timeout_s_, max_drift_m_;
  double elsewhere_m_ = -1.0;
  FaultPlan plan_;
  double hold_start_s_ = -1.0;
  bool converged_ = false;
  double converged_at_s_ = -1.0;
  std::vector<AgentId> missing_;
};

}  // namespace qswarm
