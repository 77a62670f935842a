#include "common/scenario/run_config.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>

namespace qswarm {

Vec3 RunConfig::initial_average() const {
  Vec3 sum = Vec3::Zero();
  for (const AgentSpec& a : agents) sum += a.q0();
  return agents.empty() ? sum : Vec3(sum / static_cast<double>(agents.size()));
}

bool RunConfig::has_formation() const {
  for (const AgentSpec& a : agents)
    if (!a.offset_W.isZero()) return true;
  return false;
}

const AgentSpec* RunConfig::spec(AgentId id) const {
  for (const AgentSpec& a : agents)
    if (a.id == id) return &a;
  return nullptr;
}

std::set<AgentId> RunConfig::ids() const {
  std::set<AgentId> out;
  for (const AgentSpec& a : agents) out.insert(a.id);
  return out;
}

int AgentConfig::steps_per_tick() const {
  return std::max(1, static_cast<int>(std::lround(physics_hz / consensus_hz)));
}

std::vector<Vec3> formation_slots(int shape, int n, double spacing_m) {
  // Shapes as in proto/scenario.proto: 2 line, 3 grid, 4 circle, 5 lattice; else none.
  std::vector<Vec3> out;
  if (n <= 0) return out;
  const double s = spacing_m;
  const auto centred = [](int k, int count) { return k - (count - 1) / 2.0; };
  switch (shape) {
    case 2:
      for (int k = 0; k < n; ++k) out.emplace_back(centred(k, n) * s, 0.0, 0.0);
      break;
    case 3: {
      const int cols = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n))));
      const int rows = (n + cols - 1) / cols;
      for (int k = 0; k < n; ++k)
        out.emplace_back(centred(k % cols, cols) * s, centred(k / cols, rows) * s, 0.0);
      break;
    }
    case 4: {
      // Neighbouring slots spacing_m apart: the chord 2 R sin(pi / n) equals the spacing.
      const double r = n == 1 ? 0.0 : n == 2 ? s / 2.0 : s / (2.0 * std::sin(std::numbers::pi / n));
      for (int k = 0; k < n; ++k) {
        const double a = 2.0 * std::numbers::pi * k / n;
        out.emplace_back(r * std::cos(a), r * std::sin(a), 0.0);
      }
      break;
    }
    case 5: {
      // The smallest side whose cube holds n (cbrt(27) is 3.0000000000000004: no ceil of it).
      int side = std::max(1, static_cast<int>(std::lround(std::cbrt(static_cast<double>(n)))));
      while (side * side * side < n) ++side;
      while (side > 1 && (side - 1) * (side - 1) * (side - 1) >= n) --side;
      const int layers = (n + side * side - 1) / (side * side);
      const int rows = std::min(side, (n + side - 1) / side);
      for (int k = 0; k < n; ++k) {
        out.emplace_back(centred(k % side, side) * s, centred((k / side) % side, rows) * s,
                         centred(k / (side * side), layers) * s);
      }
      break;
    }
    default:
      out.assign(static_cast<std::size_t>(n), Vec3::Zero());
      return out;
  }
  // The formation's centroid is the agreed centre.
  Vec3 mean = Vec3::Zero();
  for (const Vec3& v : out) mean += v;
  mean /= static_cast<double>(n);
  for (Vec3& v : out) v -= mean;
  return out;
}

std::set<AgentId> RunConfig::held_agents() const {
  std::set<AgentId> held;
  if (!agent.avoidance.enabled) return held;
  for (const AgentSpec& a : agents)
    for (const AgentSpec& b : agents)
      if (a.id != b.id && (a.offset_W - b.offset_W).norm() < agent.avoidance.filter_distance_m())
        held.insert(a.id);
  return held;
}

std::vector<AgentSpec> random_agent_specs(int n, std::uint64_t seed, double box_m,
                                          double min_separation_m) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, box_m);
  std::vector<AgentSpec> out;
  for (int i = 0; i < n; ++i) {
    for (int attempt = 0;; ++attempt) {
      if (attempt == 10000) {
        throw std::runtime_error("no room for " + std::to_string(n) + " agents " +
                                 std::to_string(min_separation_m) + " m apart");
      }
      const double x = u(rng), y = u(rng), z = u(rng);
      const Vec3 p(x, y, z);
      const bool clear = std::all_of(out.begin(), out.end(), [&](const AgentSpec& a) {
        return (a.position_W - p).norm() >= min_separation_m;
      });
      if (!clear) continue;
      out.push_back({static_cast<AgentId>(i + 1), p, 0.0});
      break;
    }
  }
  return out;
}

}  // namespace qswarm
