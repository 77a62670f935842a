// swarm-preview: flies the paper's time-varying weighted rendezvous (section 2, "Rendezvous
// Mission, Time-varying Weighted Network") in one process with the same per-agent law the agent
// processes run, and prints where the agents met against the paper's point.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "common/core/graph.hpp"
#include "common/sim/lockstep_laws.hpp"

int main(int argc, char** argv) {
  using namespace qswarm;
  LawKind kind = LawKind::kEdgeFlow;
  double rate_hz = 50.0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    try {
      if (a == "--law" && i + 1 < argc) {
        kind = parse_law_kind(argv[++i]);
      } else if (a == "--rate" && i + 1 < argc) {
        rate_hz = std::stod(argv[++i]);
        if (!(rate_hz > 0.0)) throw std::invalid_argument("--rate: expected a value > 0");
      } else if (a == "--help" || a == "-h") {
        std::printf("usage: swarm-preview [--law edge-flow|laplacian] [--rate HZ]\n");
        return 0;
      } else {
        std::fprintf(stderr, "swarm-preview: unknown argument '%s' (try --help)\n", a.c_str());
        return 2;
      }
    } catch (const std::exception& e) {
      std::fprintf(stderr, "swarm-preview: %s\n", e.what());
      return 2;
    }
  }
  LockstepConfig cfg;
  cfg.agents = {{1, {16, 5, 36}}, {2, {19, 19, 29}}, {3, {12, 16, 33}}, {4, {14, 1, 26}}};
  cfg.law.kind = kind;
  cfg.law.weight.policy = WeightPolicy::kDistance;
  cfg.law.topology.policy = TopologyPolicy::kStickyProximity;
  cfg.law.topology.threshold_m = 12.5;
  cfg.consensus_rate_hz = rate_hz;
  LockstepLaws swarm(cfg);

  const Vec3 paper(15.25, 10.25, 31.0);
  std::printf(
      "paper's time-varying rendezvous, %s law, %.0f Hz, sticky proximity 12.5 m, w = distance\n",
      to_string(kind).c_str(), rate_hz);
  std::printf("%8s %6s %10s %14s\n", "t [s]", "edges", "lambda2", "disagree [m]");
  double next_print = 0.0;
  std::size_t edges_before = swarm.edges().size();
  while (swarm.time_s() < 60.0 && disagreement(swarm.states()) > 1e-3) {
    const auto edges = swarm.edges();
    if (swarm.time_s() >= next_print || edges.size() != edges_before) {
      const Spectrum s = analyze(laplacian(swarm.size(), edges));
      std::printf("%8.2f %6zu %10.4f %14.6f\n", swarm.time_s(), edges.size(), s.lambda2,
                  disagreement(swarm.states()));
      next_print += 5.0;
      edges_before = edges.size();
    }
    swarm.step();
  }
  const Vec3 met = average(swarm.states());
  std::printf("\nmet after %.2f s (disagreement %.2e m)\n", swarm.time_s(),
              disagreement(swarm.states()));
  for (int i = 0; i < swarm.size(); ++i) {
    const Vec3 q = swarm.states()[i];
    std::printf("  agent %d at (%.4f, %.4f, %.4f)\n", i + 1, q.x(), q.y(), q.z());
  }
  std::printf("mean     (%.6f, %.6f, %.6f)\npaper q*  (%.6f, %.6f, %.6f)\n|mean - q*| = %.3e m\n",
              met.x(), met.y(), met.z(), paper.x(), paper.y(), paper.z(), (met - paper).norm());
  return (met - paper).norm() < 1e-6 ? 0 : 1;
}
