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

// What law W_MSR needs of the initial graph: `swarm inspect` shows it, `swarm run` refuses a FIXED
// graph that lacks it (it can never gain it) and warns about any other.
ResilienceCheck resilience_of(const RunConfig& rc, const InitialGraph& g);
std::string describe(const ResilienceCheck& c, const RunConfig& rc);

// The run plan in a few lines, as `swarm inspect` prints it.
std::string describe_plan(const RunPlan& p);

// `swarm inspect`: the scenario's initial graph, Laplacian, spectrum and predicted agreement,
// as text or (json) as the Inspection message in JSON. Exit code: 0, or 2 for a bad scenario.
int inspect_scenario(const std::string& path, bool json);

}  // namespace qswarm
