#include "common/record/separation.hpp"

#include <algorithm>
#include <cmath>

#include "common/core/avoidance.hpp"

namespace qswarm {

void SeparationMonitor::on_sample(AgentId id, const Vec3& p_W, const Vec3& v_W, double t_s) {
  if (!p_W.allFinite() || !v_W.allFinite() || !std::isfinite(t_s)) return;
  for (const auto& [other, l] : last_) {
    if (other == id) continue;
    const double d = (p_W - project_position(l.p, l.v, t_s - l.t)).norm();
    const auto pair = std::minmax(id, other);
    if (d < min_m_) {
      min_m_ = d;
      min_t_s_ = t_s;
      min_pair_ = pair;
    }
    if (d < safe_m_) {
      if (inside_.insert(pair).second) ++violations_;
    } else if (d > safe_m_ + kRearmM) {
      inside_.erase(pair);
    }
  }
  last_[id] = {p_W, v_W, t_s};
}

void SeparationMonitor::forget(AgentId id) {
  last_.erase(id);
  for (auto it = inside_.begin(); it != inside_.end();)
    it = it->first == id || it->second == id ? inside_.erase(it) : std::next(it);
}

}  // namespace qswarm
