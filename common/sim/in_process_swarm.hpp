#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "common/core/graph.hpp"
#include "common/core/update_law.hpp"
#include "common/transport/neighbor_bus.hpp"

namespace qswarm {

struct SwarmAgentSpec {
  AgentId id = 0;
  Vec3 q0 = Vec3::Zero();
};

struct InProcessSwarmConfig {
  std::vector<SwarmAgentSpec> agents;
  LawConfig law;
  double consensus_rate_hz = 50.0;
};

// N agents running the per-agent law over an in-memory bus in lockstep: every tick each agent reads
// the others' messages from the previous tick, all step, then all publish. Deterministic.
class InProcessSwarm {
 public:
  explicit InProcessSwarm(InProcessSwarmConfig cfg);

  void step();
  // Steps until the disagreement is below tol_m or max_time_s passes; returns whether it converged.
  bool run_until_converged(double tol_m, double max_time_s);

  double time_s() const { return time_s_; }
  double dt_s() const { return 1.0 / cfg_.consensus_rate_hz; }
  int size() const { return static_cast<int>(laws_.size()); }
  Positions states() const;
  Positions initial_states() const;
  // The graph as the agents currently see it: an edge when either endpoint holds the link
  // (weight as the lower id computes it), by index into agents.
  std::vector<Edge> edges() const;
  const UpdateLaw& law(int index) const { return *laws_[index]; }

  // n agents uniformly in a cube of side box_m from a seeded generator (ids 1..n).
  static std::vector<SwarmAgentSpec> random_agents(int n, std::uint64_t seed, double box_m);

 private:
  InProcessSwarmConfig cfg_;
  std::vector<std::unique_ptr<UpdateLaw>> laws_;
  InMemoryBus bus_;
  double time_s_ = 0.0;
};

}  // namespace qswarm
