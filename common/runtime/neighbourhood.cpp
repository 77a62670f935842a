#include "common/runtime/neighbourhood.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace qswarm {
namespace {

Eigen::Vector3i cell_of(const Vec3& x, double cell_m) {
  const auto c = [&](double v) {
    // Far-off coordinates stay far off without overflowing (a sample is never beyond 1000 km);
    // a NaN goes to the origin (such an agent's samples are refused anyway).
    if (std::isnan(v)) return 0;
    return static_cast<int>(std::clamp(std::floor(v / cell_m), -1e9, 1e9));
  };
  return {c(x.x()), c(x.y()), c(x.z())};
}

std::string cell_name(char tag, const Eigen::Vector3i& c) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%c%d.%d.%d", tag, c.x(), c.y(), c.z());
  return buf;
}

// A box's centre: where x is, kept within the same bounds as cells (a NaN goes to the origin:
// such an agent's samples are refused anyway).
Vec3 clamped(const Vec3& x) {
  Vec3 out;
  for (int k = 0; k < 3; ++k) out[k] = std::isfinite(x[k]) ? std::clamp(x[k], -1e9, 1e9) : 0.0;
  return out;
}

// Whether x lies within `keep_m` of cell c (its box grown by keep_m on every side).
bool near_cell(const Vec3& x, const Eigen::Vector3i& c, double cell_m, double keep_m) {
  for (int k = 0; k < 3; ++k) {
    const double lo = c[k] * cell_m - keep_m, hi = (c[k] + 1) * cell_m + keep_m;
    if (x[k] < lo || x[k] >= hi) return false;
  }
  return true;
}

void sort_unique(std::vector<std::string>& v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
}

}  // namespace

double Neighbourhood::margin_m(double reach_m) { return std::max(1.0, 0.25 * reach_m); }

Neighbourhood::Neighbourhood(const RunConfig& rc, AgentId self) : self_(self) {
  const TopologyConfig& t = rc.agent.law.topology;
  whole_run_ = rc.plan.delivery == Delivery::kAll;
  reach_ = rc.plan.delivery == Delivery::kReach;
  for (const auto& [a, b] : t.edges) {
    if (a == self) listed_.insert(b);
    if (b == self) listed_.insert(a);
  }
  // Links that outlive the reach (sticky proximity keeps them however far) are heard by name;
  // other links lie within the reach, which the cells cover (and naming them would move the
  // partitions, and make DDS re-match, at every link that comes and goes).
  by_name_ = t.policy == TopologyPolicy::kStickyProximity;
  const double reach = t.threshold_m + t.hysteresis_m;
  // A sender within the reach plus margin of the listener lies in a cell at most kSpan cells
  // away: the two keep their cells up to keep_m outside them, so cells kSpan + 1 apart leave
  // kSpan * cell_m - 2 * keep_m = the reach plus margin between them. Finer cells than one reach
  // wide listen to less space around the agent (5 cells of half the width: 0.83 times as far each
  // way, so its cells hold 0.69 times the senders in a plane and 0.58 times in space), for more
  // partitions per reader and more frequent moves.
  const auto space = [&](char tag, double r) {
    const double keep = 0.5 * margin_m(r), radius = r + margin_m(r);
    spaces_.push_back(
        {tag, (radius + 2.0 * keep) / kSpan, keep, radius, std::nullopt, std::nullopt, {}, {}});
  };
  if (t.policy == TopologyPolicy::kProximity || t.policy == TopologyPolicy::kStickyProximity)
    space('q', reach);
  double physical = t.policy == TopologyPolicy::kRange ? reach : 0.0;
  // The avoidance filter acts on the plants within its distance; its reach here also covers a
  // second of closing at the reference's top speed.
  if (rc.agent.avoidance.enabled && rc.agent.plant_spec().follows_reference)
    physical = std::max(
        physical, rc.agent.avoidance.filter_distance_m() + 2.0 * rc.agent.reference_speed_mps);
  if (physical > 0.0) space('p', physical);
}

Interest Neighbourhood::update(const Vec3& p_W, const Vec3& q, const std::set<AgentId>& linked,
                               const Settling& settling) {
  Interest in;
  if (whole_run_) return in;
  in.publish.push_back(agent_partition(self_));
  for (Space& s : spaces_) {
    const Vec3& x = s.tag == 'q' ? q : p_W;
    if (!s.cell || !near_cell(x, *s.cell, s.cell_m, s.keep_m)) {
      s.cell = cell_of(x, s.cell_m);
      s.cell_name = cell_name(s.tag, *s.cell);
      s.listened = cells_about(s.cell_name, kSpan);
      std::sort(s.listened.begin(), s.listened.end());
    }
    if (reach_) {
      if (!s.anchor || !((x - *s.anchor).cwiseAbs().maxCoeff() <= s.keep_m)) s.anchor = clamped(x);
      const Vec3 keep = Vec3::Constant(s.keep_m);
      in.near.push_back({s.tag, *s.anchor - keep, *s.anchor + keep, s.radius_m});
    }
    in.publish.push_back(s.cell_name);
    in.subscribe.insert(in.subscribe.end(), s.listened.begin(), s.listened.end());
  }
  if (reach_ && !spaces_.empty()) {
    in.subscribe.push_back(inbox_partition(self_));
    std::map<AgentId, int> ticks;
    std::set<AgentId> pushing;
    for (const auto& [id, heard] : settling) {
      if (id == self_) continue;
      const auto it = settling_.find(id);
      const int n = ticks[id] = it == settling_.end() ? 1 : it->second + 1;
      if (!heard || n >= 3 || pushing_.count(id)) pushing.insert(id);
    }
    settling_ = std::move(ticks);
    pushing_ = std::move(pushing);
    for (const AgentId id : pushing_) in.publish.push_back(inbox_partition(id));
  }
  for (const AgentId id : listed_) in.subscribe.push_back(agent_partition(id));
  if (by_name_)
    for (const AgentId id : linked)
      if (id != self_) in.subscribe.push_back(agent_partition(id));
  sort_unique(in.publish);
  sort_unique(in.subscribe);
  return in;
}

std::vector<Interest> Neighbourhood::interests_at_start(const RunConfig& rc) {
  std::vector<Interest> out;
  out.reserve(rc.agents.size());
  for (const AgentSpec& a : rc.agents)
    out.push_back(Neighbourhood(rc, a.id).update(a.position_W, a.q0(), {}));
  return out;
}

std::set<AgentId> Neighbourhood::heard_at_start(const RunConfig& rc, AgentId id) {
  std::set<AgentId> out;
  const AgentSpec* me = rc.spec(id);
  if (!me) return out;
  const std::vector<Interest> in = interests_at_start(rc);
  const Interest& mine = in[static_cast<std::size_t>(me - rc.agents.data())];
  for (std::size_t j = 0; j < rc.agents.size(); ++j) {
    const AgentSpec& a = rc.agents[j];
    if (a.id != id && Interest::hears(mine, in[j], a.q0(), a.position_W)) out.insert(a.id);
  }
  return out;
}

std::set<AgentId> start_peers(const RunConfig& rc, AgentId id) {
  std::set<AgentId> peers;
  const TopologyConfig& t = rc.agent.law.topology;
  if (t.policy == TopologyPolicy::kFixed && rc.plan.delivery == Delivery::kAll) {
    peers = listed_peers(t, id);  // everyone is heard, but only the listed are neighbours
  } else {
    peers = Neighbourhood::heard_at_start(rc, id);
    if (t.policy == TopologyPolicy::kFixed) {
      // Under avoidance physical neighbours are heard too; the law waits only for its graph.
      const std::set<AgentId> listed = listed_peers(t, id);
      std::set<AgentId> both;
      for (const AgentId p : peers)
        if (listed.count(p)) both.insert(p);
      peers = both;
    }
  }
  for (const AgentId late : rc.faults.late_joiners()) peers.erase(late);
  return peers;
}

}  // namespace qswarm
