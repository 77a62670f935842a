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
// flows). Under W-MSR with F (outliers_f > 0), which promises the agents that do not lie agreement
// inside their initial bounding box: agreeing outside it is no convergence (more than F liars, or a
// graph not robust enough), and when all but at most F agents agree for hold_s plus the neighbour
// timeout while those F stay away (the snapshot's trimmed_agents), the run ends naming them: a
// liar and an agent cut off look the same from here, and either way not every agent agreed.
// Pure.
class ConvergenceJudge {
 public:
  enum class Verdict {
    kNone,
    kConverged,
    kAgreedWithoutSome,
    kAgreedElsewhere,
    kAgreedExceptOutliers
  };
  // max_drift_m < 0: the law does not keep the average (laplacian, w-msr), no such check.
  ConvergenceJudge(double tolerance_m, double hold_s, double timeout_s, double max_drift_m,
                   FaultPlan plan, int outliers_f = 0);
  // Feed each graph snapshot; returns a verdict the first time one is reached.
  Verdict update(double t_s, const records::GraphSnapshot& g, const Presence& presence);
  bool converged() const { return converged_; }
  bool agreed_without_some() const { return !missing_.empty(); }
  // W-MSR: the agents whose states stayed away while the others agreed (empty: none such).
  const std::vector<AgentId>& outliers() const { return outliers_; }
  // The agents agreed, but max_drift_m or more away from the initial average: how far (-1: no).
  // (Under W-MSR: how far outside the agreeing agents' initial bounding box.)
  double agreed_elsewhere_m() const { return elsewhere_m_; }
  // The agents the run expected that were not running when the others agreed.
  const std::vector<AgentId>& missing() const { return missing_; }
  // Start of the hold that ended in a verdict (-1 before).
  double converged_at_s() const { return converged_at_s_; }

 private:
  std::vector<AgentId> missing_now(double t_s, const Presence& presence) const;
  // Whether every agent due alive was heard after `since_s`: one frozen just as the others agreed
  // (SIGSTOP, a hung host) is not yet known gone, and its last word cannot vouch for the hold.
  bool all_heard_after(double since_s, double t_s, const Presence& presence) const;
  Verdict judge_outliers(double t_s, const records::GraphSnapshot& g, bool ready);
  double tolerance_m_, hold_s_, timeout_s_, max_drift_m_;
  double elsewhere_m_ = -1.0;
  FaultPlan plan_;
  int outliers_f_;
  double hold_start_s_ = -1.0;
  double except_start_s_ = -1.0;  // the hold of all but the trimmed agents
  std::vector<AgentId> outliers_;
  bool converged_ = false;
  double converged_at_s_ = -1.0;
  std::vector<AgentId> missing_;
};

}  // namespace qswarm
