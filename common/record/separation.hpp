#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <utility>

#include "common/core/math.hpp"
#include "common/core/topology.hpp"

namespace qswarm {

// The swarm's physical separation over a whole run, judged on every sample (not only on the 10 Hz
// graph rows): a sample of one agent is measured against the newest sample of every other present
// agent, moved to the same instant by project_position() (the rule the agents' filters use).
// Counts violations of the safe distance: a pair closer than it is one violation until the pair
// is more than kRearmM beyond it again (a pair hovering at the boundary counts once). Pure: told
// the samples and departures.
class SeparationMonitor {
 public:
  static constexpr double kRearmM = 0.05;
  explicit SeparationMonitor(double safe_distance_m) : safe_m_(safe_distance_m) {}

  // Agent `id` was at p_W with velocity v_W at swarm time t_s.
  void on_sample(AgentId id, const Vec3& p_W, const Vec3& v_W, double t_s);
  // The agent has departed: its quadcopter no longer counts (until its next sample).
  void forget(AgentId id);

  bool measured() const { return min_m_ < 1e299; }
  double min_m() const { return min_m_; }
  double min_t_s() const { return min_t_s_; }
  std::pair<AgentId, AgentId> min_pair() const { return min_pair_; }
  std::uint32_t violations() const { return violations_; }

 private:
  struct Last {
    Vec3 p, v;
    double t;
  };
  double safe_m_;
  std::map<AgentId, Last> last_;
  std::set<std::pair<AgentId, AgentId>> inside_;  // pairs now closer than the safe distance
  double min_m_ = 1e300;
  double min_t_s_ = 0.0;
  std::pair<AgentId, AgentId> min_pair_{0, 0};
  std::uint32_t violations_ = 0;
};

}  // namespace qswarm
