#pragma once

#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include "common/core/graph.hpp"
#include "proto/records.pb.h"

namespace qswarm {

using LinksOf = std::function<const std::vector<std::pair<AgentId, double>>&(int)>;

// What a W-MSR run's snapshot measures beyond the rest: the law's F, the run's tolerance, and each
// agent's initial consensus state (in the order of ids).
struct WmsrMeasure {
  int f = 0;
  double tolerance_m = 0.0;
  Positions q0;
};

// The last graph's spectrum, kept so that a graph that has not changed (same agents, same edges,
// same weights: a fixed topology, or a range topology at rest) is not decomposed again: at 256
// agents a decomposition is milliseconds, ten times a second of swarm time.
struct SpectrumMemo {
  std::vector<AgentId> ids;
  std::vector<Edge> edges;
  double lambda2 = 0.0;
  int components = 0;
  bool valid = false;
  std::uint64_t reused = 0, computed = 0;
};

// One snapshot of the swarm's graph and geometry: the edges the agents hold (an edge when either
// end holds it), lambda_2 and components of its Laplacian, disagreement of the consensus states q,
// drift of their mean from `initial_average`, the smallest separation of the physical positions p
// (and between whom), and their largest distance from their slots (mean of q + `offsets`, one per
// agent; empty: no formation). An agent with held[i] (a neighbour holds it off a slot that
// avoidance cannot let it reach) does not count toward the spread. Every snapshot has the fewest
// neighbours an agent reads; with `wmsr`, the states farthest from the others taken out (at most
// F) and the rest's agreement, spread and distance from their initial box. Pure, but for `memo`
// (if given: the spectrum of the last graph measured with it).
records::GraphSnapshot measure_graph(double t_s, const std::vector<AgentId>& ids,
                                     const Positions& q, const Positions& p,
                                     const LinksOf& links_of, const Vec3& initial_average,
                                     const Positions& offsets = {},
                                     const std::vector<bool>& held = {},
                                     const WmsrMeasure* wmsr = nullptr,
                                     SpectrumMemo* memo = nullptr);

}  // namespace qswarm
