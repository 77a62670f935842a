// Core benchmarks: what one agent spends per physics step, per control step and per consensus
// tick, and what the supervisor spends analysing an N-agent graph.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "common/core/avoidance.hpp"
#include "common/core/dynamics.hpp"
#include "common/core/graph.hpp"
#include "common/core/tracking_controller.hpp"
#include "common/core/update_law.hpp"

namespace qswarm {
namespace {

void BM_Rk4Step(benchmark::State& state) {
  const Airframe af = Airframe::paper();
  QuadState s;
  s.omega_B = Vec3(0.1, -0.2, 0.3);
  const RotorSpeeds w(200, 195, 198, 201);
  for (auto _ : state) {
    s = rk4_step(af, s, w, 0.002);
    benchmark::DoNotOptimize(s);
  }
}
BENCHMARK(BM_Rk4Step);

void BM_ControllerStep(benchmark::State& state) {
  const Airframe af = Airframe::paper();
  const TrackingGains gains;
  QuadState s;
  s.R_WB = rotation_from_tait_bryan({0.1, -0.1, 0.5});
  TrackingReference ref;
  ref.p_W = Vec3(3, 4, 1);
  for (auto _ : state) {
    TrackingOutput out = track(af, gains, s, ref);
    benchmark::DoNotOptimize(out);
  }
}
BENCHMARK(BM_ControllerStep);

// The avoidance filter at one physics step, with k neighbours all close enough to constrain the
// desired velocity (the worst case: every one enters the QP; at most 8 are kept, the nearest).
void BM_SafeVelocity(benchmark::State& state) {
  const int k = static_cast<int>(state.range(0));
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> angle(0.0, 6.283185307179586);
  std::vector<Obstacle> others;
  for (int i = 0; i < k; ++i) {
    const double a = angle(rng), b = angle(rng) / 4.0;
    others.push_back({static_cast<AgentId>(i + 2),
                      Vec3(std::cos(a) * std::cos(b), std::sin(a) * std::cos(b), std::sin(b)) *
                          (1.4 + 0.1 * i)});
  }
  AvoidanceConfig c;
  c.enabled = true;
  for (auto _ : state) {
    SafeVelocity v = safe_velocity(1, Vec3::Zero(), Vec3(3, 0, 0), Vec3(10, 0, 0), others, c);
    benchmark::DoNotOptimize(v);
  }
}
BENCHMARK(BM_SafeVelocity)->Arg(1)->Arg(4)->Arg(8)->Arg(15);

std::vector<NeighborView> neighbours(int k, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-10, 10);
  std::vector<NeighborView> out;
  for (int i = 0; i < k; ++i) {
    NeighborView v;
    v.id = static_cast<AgentId>(i + 2);  // self is 1: it owns every edge
    v.q = Vec3(u(rng), u(rng), u(rng));
    v.total_weight = 10.0;
    v.seq = 1;
    out.push_back(v);
  }
  return out;
}

void BM_ConsensusUpdate(benchmark::State& state, const char* law_name) {
  const int k = static_cast<int>(state.range(0));
  LawConfig cfg;
  cfg.law = law_name;
  cfg.weight.policy = WeightPolicy::kDistance;
  cfg.topology.policy = TopologyPolicy::kProximity;
  cfg.topology.threshold_m = 1e3;  // every neighbour linked
  const auto law = make_law(1, Vec3::Zero(), cfg);
  const std::vector<NeighborView> nbrs = neighbours(k, 11);
  for (auto _ : state) {
    law->step(0.02, nbrs);
    benchmark::DoNotOptimize(law->state());
  }
  state.SetComplexityN(k);
}
BENCHMARK_CAPTURE(BM_ConsensusUpdate, edge_flow, "edge-flow")->RangeMultiplier(2)->Range(1, 64);
BENCHMARK_CAPTURE(BM_ConsensusUpdate, laplacian, "laplacian")->RangeMultiplier(2)->Range(1, 64);

void BM_SpectralAnalysis(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0, 50);
  std::vector<Vec3> p(n);
  for (auto& x : p) x = Vec3(u(rng), u(rng), u(rng));
  std::vector<Edge> edges;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      if ((p[i] - p[j]).norm() < 25.0) edges.push_back({i, j, (p[i] - p[j]).norm()});
  for (auto _ : state) {
    const Spectrum s = analyze(laplacian(n, edges));
    benchmark::DoNotOptimize(s.lambda2);
  }
  state.SetComplexityN(n);
}
BENCHMARK(BM_SpectralAnalysis)->RangeMultiplier(2)->Range(4, 256)->Complexity();

// W-MSR's exhaustive (F+1, F+1)-robustness check (F = 1) on n agents, as the recorder runs it once
// per distinct graph: a circulant graph where each agent links to the `reach` nearest on each
// side of a ring (reach n/2: the complete graph). Sparse graphs that hold the condition are the
// slow case: fewer sets satisfy it alone, so more pairs are tried.
void BM_RobustnessCheck(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const int reach = static_cast<int>(state.range(1));
  std::vector<Edge> edges;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      if (std::min(j - i, n - (j - i)) <= reach) edges.push_back({i, j, 1.0});
  bool robust = false;
  for (auto _ : state) {
    robust = is_rs_robust(n, edges, 2, 2);
    benchmark::DoNotOptimize(robust);
  }
  state.SetLabel(robust ? "robust" : "not robust");
}
BENCHMARK(BM_RobustnessCheck)
    ->Args({7, 3})
    ->Args({10, 2})
    ->Args({10, 5})
    ->Args({14, 2})
    ->Args({14, 3})
    ->Args({14, 7})
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace qswarm

BENCHMARK_MAIN();
