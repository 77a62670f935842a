#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "common/core/agent.hpp"

namespace qswarm {

// How an edge's weight follows from the distance between its two agents' states.
enum class WeightPolicy {
  kUnweighted,       // w = 1 (paper, unweighted networks)
  kDistance,         // w = |q_i - q_j| now (paper's time-varying weighted example)
  kInitialDistance,  // w = |q_i(0) - q_j(0)|, fixed (the paper's fixed weighted example)
  kInverseDistance,  // w = scale / max(|q_i - q_j|, 1 cm): strong when close, like a radio link
};

struct WeightConfig {
  WeightPolicy policy = WeightPolicy::kDistance;
  double scale = 1.0;  // multiplies every weight
};

double weight_for_distance(const WeightConfig& cfg, double distance_m);

// Which agents are linked.
enum class TopologyPolicy {
  kFixed,            // exactly the listed edges (the paper's fixed networks)
  kProximity,        // listed edges, plus an edge while distance <= threshold (drops past
                     // threshold + hysteresis)
  kStickyProximity,  // listed edges, plus any edge once distance <= threshold; added edges stay
                     // (the paper's time-varying example)
  kRange,            // like kProximity, but on the agents' physical distance (radio range), which
                     // the runtime gives the law (NeighborView::link_distance_m)
};

struct TopologyConfig {
  TopologyPolicy policy = TopologyPolicy::kStickyProximity;
  double threshold_m = 12.5;
  double hysteresis_m = 0.5;
  std::vector<std::pair<AgentId, AgentId>> edges;  // fixed graph, or the initial edges
};

std::string to_string(WeightPolicy p);
std::string to_string(TopologyPolicy p);
// Throw std::invalid_argument naming the accepted values.
WeightPolicy parse_weight_policy(const std::string& s);
TopologyPolicy parse_topology_policy(const std::string& s);

// The peers the configured edge list names for `self` (its whole graph under kFixed).
std::set<AgentId> listed_peers(const TopologyConfig& cfg, AgentId self);

// One agent's view of its own links: decides, from distances it observes, whether it is linked to
// each peer it hears. Pure state machine; no clock.
class LinkTracker {
 public:
  LinkTracker(AgentId self, TopologyConfig cfg);

  // Returns whether self is linked to `peer` at this distance, updating the sticky/hysteresis
  // state.
  bool update(AgentId peer, double distance_m);
  // The peer went silent: its link is gone until it is heard again (sticky links come back then).
  void forget(AgentId peer);
  bool listed(AgentId peer) const { return listed_.count(peer) > 0; }
  bool linked(AgentId peer) const { return linked_.count(peer) > 0; }
  const TopologyConfig& config() const { return cfg_; }

 private:
  AgentId self_;
  TopologyConfig cfg_;
  std::set<AgentId> listed_;  // peers named by the configured edge list
  std::set<AgentId> linked_;
  std::set<AgentId> ever_linked_;
};

}  // namespace qswarm
