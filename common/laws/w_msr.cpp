// W-MSR (LeBlanc, Zhang, Koutsoukos, Sundaram, IEEE JSAC 2013): the Laplacian step after trimming
// up to F extreme neighbour values a coordinate (WmsrLaw).
#include "common/core/law_registry.hpp"

namespace qswarm::laws {

LawSpec w_msr() {
  LawSpec s;
  s.name = "w-msr";
  s.aliases = {"w_msr", "wmsr", "W_MSR"};
  s.summary = "trims F extreme neighbour values: honest agents stay in their initial range";
  s.params = {{"f", 0, 64, 1, true, "lying agents tolerated, in all"}};
  // It agrees only where the graph is (F+1, F+1)-robust, which the paper's sparse graphs are not
  // (an agent with one neighbour trims it): no claim on the paper's scenarios.
  s.claims.agreement = false;
  s.claims.honest_hull = true;
  s.make = [](AgentId self, const Vec3& q0, const LawConfig& cfg) {
    return std::make_unique<WmsrLaw>(self, q0, cfg);
  };
  return s;
}

}  // namespace qswarm::laws
