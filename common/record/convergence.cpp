#include "common/record/convergence.hpp"

namespace qswarm {

ConvergenceJudge::ConvergenceJudge(double tolerance_m, double hold_s, FaultPlan plan)
    : tolerance_m_(tolerance_m), hold_s_(hold_s), plan_(std::move(plan)) {}

bool ConvergenceJudge::everyone_due_is_back(double t_s, const Presence& presence) const {
  // Every agent not joining late must have been seen at least once.
  if (presence.seen_count() + plan_.late_join.size() < presence.tracks().size()) return false;
  for (const auto& [id, track] : presence.tracks()) {
    if (plan_.due_back(id, t_s) && !presence.running(id)) return false;
  }
  return true;
}

bool ConvergenceJudge::update(double t_s, const records::GraphSnapshot& g,
                              const Presence& presence) {
  const bool agree = g.agents() > 0 && everyone_due_is_back(t_s, presence) &&
                     t_s >= plan_.last_fault_end_s() && g.disagreement_m() < tolerance_m_ &&
                     g.spread_m() < tolerance_m_;
  if (!agree) {
    hold_start_s_ = -1.0;
    return false;
  }
  if (hold_start_s_ < 0.0) hold_start_s_ = t_s;
  if (!converged_ && t_s - hold_start_s_ >= hold_s_) {
    converged_ = true;
    converged_at_s_ = hold_start_s_;
    return true;
  }
  return false;
}

}  // namespace qswarm
