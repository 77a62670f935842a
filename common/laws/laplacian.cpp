// The paper's law as it writes it (section 2): dq_i/dt = -k sum_j w_ij (q_i - q_j) (LaplacianLaw).
#include "common/core/law_registry.hpp"

namespace qswarm::laws {

LawSpec laplacian() {
  LawSpec s;
  s.name = "laplacian";
  s.aliases = {"LAPLACIAN"};
  s.summary = "the paper's law as written: agreement, the average only without loss";
  s.make = [](AgentId self, const Vec3& q0, const LawConfig& cfg) {
    return std::make_unique<LaplacianLaw>(self, q0, cfg);
  };
  return s;
}

}  // namespace qswarm::laws
