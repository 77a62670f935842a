#include "common/record/convergence.hpp"

namespace qswarm {

ConvergenceJudge::ConvergenceJudge(double tolerance_m, double hold_s, double timeout_s,
                                   double max_drift_m, FaultPlan plan, int outliers_f)
    : tolerance_m_(tolerance_m),
      hold_s_(hold_s),
      timeout_s_(timeout_s),
      max_drift_m_(max_drift_m),
      plan_(std::move(plan)),
      outliers_f_(outliers_f) {}

std::vector<AgentId> ConvergenceJudge::missing_now(double t_s, const Presence& presence) const {
  std::vector<AgentId> out;
  for (const auto& [id, track] : presence.tracks())
    if (plan_.due_alive(id, t_s) && !presence.running(id)) out.push_back(id);
  return out;
}

bool ConvergenceJudge::all_heard_after(double since_s, double t_s, const Presence& presence) const {
  for (const auto& [id, track] : presence.tracks())
    if (plan_.due_alive(id, t_s) && presence.running(id) && !(track.last_heard_s > since_s))
      return false;
  return true;
}

ConvergenceJudge::Verdict ConvergenceJudge::update(double t_s, const records::GraphSnapshot& g,
                                                   const Presence& presence) {
  if (converged_ || !missing_.empty() || elsewhere_m_ >= 0.0 || !outliers_.empty())
    return Verdict::kNone;  // once
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
  const bool ready = g.agents() > 0 && planned_back && !starting &&
                     t_s >= plan_.last_fault_end_s() &&
                     g.held_speed_mps() < tolerance_m_;  // held agents: tolerance_m per second
  const bool agree = ready && g.disagreement_m() < tolerance_m_ && g.spread_m() < tolerance_m_;
  if (!agree) {
    hold_start_s_ = -1.0;
    return judge_outliers(t_s, g, ready && missing_now(t_s, presence).empty());
  }
  except_start_s_ = -1.0;
  if (hold_start_s_ < 0.0) hold_start_s_ = t_s;
  const double held = t_s - hold_start_s_;
  const std::vector<AgentId> missing = missing_now(t_s, presence);
  if (missing.empty() && held >= hold_s_ && max_drift_m_ >= 0.0 &&
      g.mean_drift_m() > max_drift_m_) {
    elsewhere_m_ = g.mean_drift_m();
    converged_at_s_ = hold_start_s_;
    return Verdict::kAgreedElsewhere;
  }
  if (missing.empty() && held >= hold_s_ && outliers_f_ > 0 &&
      g.outside_initial_box_m() >= tolerance_m_) {
    elsewhere_m_ = g.outside_initial_box_m();
    converged_at_s_ = hold_start_s_;
    return Verdict::kAgreedElsewhere;
  }
  if (missing.empty() && held >= hold_s_ && all_heard_after(hold_start_s_, t_s, presence)) {
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

ConvergenceJudge::Verdict ConvergenceJudge::judge_outliers(double t_s,
                                                           const records::GraphSnapshot& g,
                                                           bool ready) {
  const bool rest_agree = outliers_f_ > 0 && ready && g.trimmed_agents_size() > 0 &&
                          g.trimmed_disagreement_m() < tolerance_m_ &&
                          g.trimmed_spread_m() < tolerance_m_;
  if (!rest_agree) {
    except_start_s_ = -1.0;
    return Verdict::kNone;
  }
  if (except_start_s_ < 0.0) except_start_s_ = t_s;
  // As long as for an agent that is missing: a slow but honest agent has time to come in.
  if (t_s - except_start_s_ < hold_s_ + timeout_s_) return Verdict::kNone;
  outliers_.assign(g.trimmed_agents().begin(), g.trimmed_agents().end());
  converged_at_s_ = except_start_s_;
  if (g.outside_initial_box_m() >= tolerance_m_) elsewhere_m_ = g.outside_initial_box_m();
  return Verdict::kAgreedExceptOutliers;
}

}  // namespace qswarm
