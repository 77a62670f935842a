#include "common/runtime/restart_policy.hpp"

namespace qswarm {

bool RestartPolicy::is_planned_kill(AgentId id, int marked) const {
  const auto it = kills_seen_.find(id);
  const int seen = it == kills_seen_.end() ? 0 : it->second;
  return seen < marked && seen < static_cast<int>(plan_.kills_of(id).size());
}

std::optional<double> RestartPolicy::after_planned_kill(AgentId id) {
  ++kills_seen_[id];
  const std::vector<double> times = plan_.restarts_of(id);
  int& lives = restarts_[id];
  if (lives >= static_cast<int>(times.size())) return std::nullopt;
  return times[static_cast<std::size_t>(lives++)];
}

int RestartPolicy::restarts(AgentId id) const {
  const auto it = restarts_.find(id);
  return it == restarts_.end() ? 0 : it->second;
}

}  // namespace qswarm
