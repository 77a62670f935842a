#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/core/graph.hpp"
#include "common/core/update_law.hpp"
#include "common/scenario/run_config.hpp"
#include "common/sim/liar.hpp"

namespace qswarm {

struct SwarmAgentSpec {
  AgentId id = 0;
  Vec3 q0 = Vec3::Zero();
};

struct LockstepConfig {
  std::vector<SwarmAgentSpec> agents;
  std::optional<Liar> liar;  // one of `agents` lies
  LawConfig law;
  double consensus_rate_hz = AgentConfig{}.consensus_hz;  // the run's default tick
};

// N bare agreement laws in exact lockstep: every tick each law reads the others' views from the
// previous tick, all step, then all publish. The oracle for the law's discretisation (tests compare
// it with exp(-L t) q0) and the preview tool. The product's loop (barrier, pacing, faults,
// dynamics) runs in InProcessSwarm instead.
class LockstepLaws {
 public:
  explicit LockstepLaws(LockstepConfig cfg);

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
  bool is_liar(int index) const { return cfg_.liar && laws_[index]->id() == cfg_.liar->id; }
  // The honest agents' states (all but the liar's).
  Positions honest_states() const;
  Positions honest_initial_states() const;

  // n agents uniformly in a cube of side box_m from a seeded generator (ids 1..n): the points a
  // scenario's `random_agents { count: n box_m: box_m }` with `seed` gives.
  static std::vector<SwarmAgentSpec> random_agents(int n, std::uint64_t seed, double box_m);

 private:
  LockstepConfig cfg_;
  std::vector<std::unique_ptr<UpdateLaw>> laws_;
  std::map<AgentId, NeighborView> views_;  // every law's newest view
  double time_s_ = 0.0;
};

}  // namespace qswarm
