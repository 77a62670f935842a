#include "common/core/topology.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace qswarm {

double weight_for_distance(const WeightConfig& cfg, double d) {
  switch (cfg.policy) {
    case WeightPolicy::kUnweighted:
      return cfg.scale;
    case WeightPolicy::kDistance:
    case WeightPolicy::kInitialDistance:
      return cfg.scale * d;
    case WeightPolicy::kInverseDistance:
      return cfg.scale / std::max(d, 0.01);
  }
  return cfg.scale;
}

std::string to_string(WeightPolicy p) {
  switch (p) {
    case WeightPolicy::kUnweighted:
      return "unweighted";
    case WeightPolicy::kDistance:
      return "distance";
    case WeightPolicy::kInitialDistance:
      return "initial_distance";
    case WeightPolicy::kInverseDistance:
      return "inverse_distance";
  }
  return "?";
}

std::string to_string(TopologyPolicy p) {
  switch (p) {
    case TopologyPolicy::kFixed:
      return "fixed";
    case TopologyPolicy::kProximity:
      return "proximity";
    case TopologyPolicy::kStickyProximity:
      return "sticky_proximity";
    case TopologyPolicy::kRange:
      return "range";
  }
  return "?";
}

WeightPolicy parse_weight_policy(const std::string& s) {
  for (WeightPolicy p : {WeightPolicy::kUnweighted, WeightPolicy::kDistance,
                         WeightPolicy::kInitialDistance, WeightPolicy::kInverseDistance}) {
    if (s == to_string(p)) return p;
  }
  throw std::invalid_argument(
      "weight policy '" + s +
      "': expected unweighted, distance, initial_distance or inverse_distance");
}

TopologyPolicy parse_topology_policy(const std::string& s) {
  for (TopologyPolicy p : {TopologyPolicy::kFixed, TopologyPolicy::kProximity,
                           TopologyPolicy::kStickyProximity, TopologyPolicy::kRange}) {
    if (s == to_string(p)) return p;
  }
  throw std::invalid_argument("topology policy '" + s +
                              "': expected fixed, proximity, sticky_proximity or range");
}

std::set<AgentId> listed_peers(const TopologyConfig& cfg, AgentId self) {
  std::set<AgentId> out;
  for (const auto& [a, b] : cfg.edges) {
    if (a == self) out.insert(b);
    if (b == self) out.insert(a);
  }
  return out;
}

LinkTracker::LinkTracker(AgentId self, TopologyConfig cfg) : self_(self), cfg_(std::move(cfg)) {
  if (cfg_.policy != TopologyPolicy::kFixed &&
      (!std::isfinite(cfg_.threshold_m) || cfg_.threshold_m <= 0.0)) {
    throw std::invalid_argument("topology.threshold_m: expected a finite value > 0");
  }
  if (!std::isfinite(cfg_.hysteresis_m) || cfg_.hysteresis_m < 0.0) {
    throw std::invalid_argument("topology.hysteresis_m: expected a finite value >= 0");
  }
  listed_ = listed_peers(cfg_, self_);
}

bool LinkTracker::update(AgentId peer, double d) {
  if (peer == self_) return false;
  bool link = false;
  if (listed_.count(peer)) {
    link = true;
  } else {
    switch (cfg_.policy) {
      case TopologyPolicy::kFixed:
        link = false;
        break;
      case TopologyPolicy::kProximity:
      case TopologyPolicy::kRange:
        link =
            linked_.count(peer) ? d <= cfg_.threshold_m + cfg_.hysteresis_m : d <= cfg_.threshold_m;
        break;
      case TopologyPolicy::kStickyProximity:
        link = ever_linked_.count(peer) > 0 || d <= cfg_.threshold_m;
        break;
    }
  }
  if (link) {
    linked_.insert(peer);
    ever_linked_.insert(peer);
  } else {
    linked_.erase(peer);
  }
  return link;
}

void LinkTracker::forget(AgentId peer) { linked_.erase(peer); }

}  // namespace qswarm
