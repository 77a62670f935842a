#include "common/record/convergence.hpp"

namespace qswarm {

ConvergenceJudge::ConvergenceJudge(double tolerance_m, double hold_s, double timeout_s,
                                   double max_drift_m, FaultPlan plan)
    : tolerance_m_(tolerance_m),
      hold_s_(hold_s),
      timeout_s_(timeout_s),
      max_drift_m_(max_drift_m),
      plan_(std::move(plan)) {}

std::vector<AgentId> ConvergenceJudge::missing_now(double t_s, const Presence& presence) const {
  std::vector<AgentId> out;
  for (const auto& [id, track] : presence.tracks())
    if (plan_.due_alive(id, t_s) && !presence.running(id)) out.push_back(id);
  return out;
}

ConvergenceJudge::Verdict ConvergenceJudge::update(double t_s, const records::GraphSnapshot& g,
                                                   const Presence& presence) {
  if (converged_ || !missing_.empty() || elsewhere_m_ >= 0.0) return Verdict::kNone;  // once
  // An agent the plan brings back (a due restart or late join) must be running before the hold
  // starts: its return is part of what the swarm agrees on.
  bool planned_back = true;
  // An agent still at its start barrier (present, not yet running) is not missing: the swarm has
  // not started, and agents start as their own neighbours are ready, not all at once.
  bool starting = false;
  for (const auto& [id, track] : presence.tracks()) {
    planned_back &= !plan_.due_back(id, t_s) || presence.running(id);
    starting |= plan_.due_alive(id, t_s) && track.present && !presence.running(id);
  }
  const bool agree = g.agents() > 0 && planned_back && !starting &&
                     t_s >= plan_.last_fault_end_s() && g.disagreement_m() < tolerance_m_ &&
                     g.spread_m() < tolerance_m_ &&
                     g.held_speed_mps() < tolerance_m_;  // held agents: tolerance_m per second
  if (!agree) {
    hold_start_s_ = -1.0;
    return Verdict::kNone;
  }
  if (hold_start_s_ < 0.0) hold_start_s_ = t_s;
  const double held = t_s - hold_start_s_;
  const std::vector<AgentId> missing = missing_now(t_s, presence);
  if (missing.empty() && held >= hold_s_ && max_drift_m_ >= 0.0 &&
      g.mean_drift_m() > max_drift_m_) {
    elsewhere_m_ = g.mean_drift_m();
    converged_at_s_ = hold_start_s_;
    return Verdict::kAgreedElsewhere;
  }
  if (missing.empty() && held >= hold_s_) {
    converged_ = true;
    converged_at_s_ = hold_start_s_;
    return Verdict::kConverged;
  }
  if (!missing.empty() && held >= hold_s_ + timeout_s_) {
    missing_ = missing;
    converged_at_s_ = hold_start_s_;
    return Verdict::kAgreedWithoutSome;
  }
  return Verdict::kNone;
}

}  // namespace qswarm
