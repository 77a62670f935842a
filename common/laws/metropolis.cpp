// Metropolis-Hastings weights (Xiao, Boyd and Lall, "A scheme for robust distributed sensor fusion
// based on average consensus", IPSN 2005): each tick,
//   q_i <- q_i + step * sum_j (q_j - q_i) / (1 + max(d_i, d_j))
// over the linked neighbours j, where d is an agent's number of links. The weights need no global
// knowledge (each agent sends its degree as its payload), are symmetric, and sum to less than one,
// so on a fixed graph in lockstep the swarm keeps its average and agrees at it for any connected
// graph. Unlike the paper's law the distance weights play no part, and a tick moves a fixed share
// (step), not k dt: the law is discrete in time. With a neighbour's value a tick old (over DDS),
// step below 1/2 keeps it stable, as the shipped laws' max step fraction does.
//
// Written only through the law seam (docs/laws.md): this file and one line in laws.inc.
#include <algorithm>

#include "common/core/law_registry.hpp"

namespace qswarm::laws {
namespace {

class MetropolisLaw final : public UpdateLaw {
 public:
  MetropolisLaw(AgentId self, const Vec3& q0, LawConfig cfg)
      : UpdateLaw(self, q0, std::move(cfg)), q_(q0), step_(cfg_.params.at("step")) {}
  Vec3 state() const override { return q_; }

 private:
  void integrate(const Tick& t) override {
    degree_ = 0;
    for (const double w : t.weight) degree_ += w > 0.0 ? 1 : 0;
    Vec3 dq = Vec3::Zero();
    for (std::size_t k = 0; k < t.neighbors.size(); ++k) {
      if (t.weight[k] <= 0.0) continue;
      const NeighborView& n = t.neighbors[k];
      // Its degree as it last sent it; before it said, as if it were ours.
      const double theirs = n.payload.empty() ? degree_ : n.payload[0];
      dq += step_ / (1.0 + std::max(static_cast<double>(degree_), theirs)) * (n.q - q_);
    }
    q_ += dq;
  }
  void links_observed() override {
    degree_ = 0;
    for (const auto& [peer, w] : links()) degree_ += w > 0.0 ? 1 : 0;
  }
  std::vector<double> payload() const override { return {static_cast<double>(degree_)}; }

  Vec3 q_;
  double step_;
  int degree_ = 0;
};

}  // namespace

LawSpec metropolis() {
  LawSpec s;
  s.name = "metropolis";
  s.aliases = {"metropolis-hastings"};
  s.summary = "Metropolis-Hastings weights from the two ends' degrees: discrete, no distances";
  s.params = {{"step", 0.01, 1.0, 0.5, false, "share of the weighted difference a tick moves"}};
  s.payload_max = 1;
  s.make = [](AgentId self, const Vec3& q0, const LawConfig& cfg) {
    return std::make_unique<MetropolisLaw>(self, q0, cfg);
  };
  return s;
}

}  // namespace qswarm::laws
