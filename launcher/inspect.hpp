#pragma once

#include <string>
#include <vector>

#include "common/core/graph.hpp"
#include "common/scenario/run_config.hpp"

namespace qswarm {

// The scenario's graph at t = 0 (the topology policy applied to the initial positions).
struct InitialGraph {
  std::vector<Edge> edges;
  Eigen::MatrixXd L;
  Spectrum spectrum;
};
InitialGraph initial_graph(const RunConfig& rc);

// `swarm inspect`: the scenario's initial graph, Laplacian, spectrum and predicted agreement,
// as text or (json) as the Inspection message in JSON. Exit code: 0, or 2 for a bad scenario.
int inspect_scenario(const std::string& path, bool json);

}  // namespace qswarm
