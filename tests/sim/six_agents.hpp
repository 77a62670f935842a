#pragma once

#include <string>

#include "common/scenario/run_config.hpp"
#include "common/scenario/scenario.hpp"

namespace qswarm {

// Six point agents on the complete graph, unweighted (scenarios/faults_six.txtpb): agreement is
// exponential, so the average can be checked to 1e-9. Initial average (14, 9, 20). `extra` is more
// scenario text (a fault plan).
inline RunConfig six(const std::string& extra = "") {
  static const char* kSix = R"(
name: "six"
agents { id: 1 position { x: 4 y: 17 z: 24 } }
agents { id: 2 position { x: 18 y: 10 z: 32 } }
agents { id: 3 position { x: 15 y: 10 z: 26 } }
agents { id: 4 position { x: 4 y: 2 z: 35 } }
agents { id: 5 position { x: 30 y: 5 z: 3 } }
agents { id: 6 position { x: 13 y: 10 z: 0 } }
mode: PARTICLE
law: EDGE_FLOW
weight { policy: UNWEIGHTED }
topology { policy: PROXIMITY threshold_m: 1000 }
convergence { tolerance_m: 1e-8 hold_s: 1 }
duration_s: 60
seed: 3
)";
  return resolve_scenario(parse_scenario_text(std::string(kSix) + extra, "six"));
}

}  // namespace qswarm
