// Edge-flow (DESIGN.md): the paper's Laplacian law with each edge's exchange integrated by its
// lower-id endpoint, so that the swarm's total never moves (EdgeFlowLaw).
#include "common/core/law_registry.hpp"

namespace qswarm::laws {

LawSpec edge_flow() {
  LawSpec s;
  s.name = "edge-flow";
  s.aliases = {"edge_flow", "EDGE_FLOW"};
  s.summary = "the paper's law, each edge's exchange kept by one end: the exact average";
  s.claims.exact_average = true;
  s.make = [](AgentId self, const Vec3& q0, const LawConfig& cfg) {
    return std::make_unique<EdgeFlowLaw>(self, q0, cfg);
  };
  return s;
}

}  // namespace qswarm::laws
