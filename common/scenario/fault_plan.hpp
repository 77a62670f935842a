#pragma once

#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "common/core/topology.hpp"

namespace qswarm {

// The fault plan of a run (scenario `faults`, validated). Times in simulated seconds; end 0 =
// until the end; agent 0 = any agent. It answers every question about itself that the agent, the
// launcher and the recorder ask (who joins late, who is killed or restarted when, who is due
// alive), so that the three cannot disagree.
struct FaultPlan {
  struct Loss {
    double probability = 0.0;
    AgentId from = 0, to = 0;
    double start_s = 0.0, end_s = 0.0;
  };
  struct Burst {
    double p_good_to_bad = 0.0, p_bad_to_good = 1.0, loss_good = 0.0, loss_bad = 1.0;
    AgentId from = 0, to = 0;
  };
  struct Cut {
    AgentId a = 0, b = 0;
    double start_s = 0.0, end_s = 0.0;
    bool directed = false;
  };
  struct Partition {
    std::vector<AgentId> group;
    double start_s = 0.0, end_s = 0.0;
  };
  struct Delay {
    double mean_s = 0.0, jitter_s = 0.0;
    AgentId from = 0, to = 0;
  };
  struct Kill {
    AgentId agent = 0;
    double at_s = 0.0, restart_at_s = 0.0;  // restart 0: stays dead
    bool restarts() const { return restart_at_s > at_s; }
  };
  struct LateJoin {
    AgentId agent = 0;
    double at_s = 0.0;
  };
  std::vector<Loss> loss;
  std::vector<Burst> burst;
  std::vector<Cut> cut;
  std::vector<Partition> partition;
  std::vector<Delay> delay;
  std::vector<Kill> kill;
  std::vector<LateJoin> late_join;
  std::uint32_t transport_drop_percent = 0;

  bool empty() const;
  // When the swarm's last planned fault ends (cuts, partitions, loss windows, kills' restarts,
  // late joins): the supervisor judges convergence only after it.
  double last_fault_end_s() const;

  // The simulated time at which `id` joins late, if it does.
  std::optional<double> late_join_at(AgentId id) const;
  std::set<AgentId> late_joiners() const;
  // Planned kills of `id` at or after from_s, in time order (a restarted process skips the kills
  // its predecessors already suffered).
  std::vector<double> kills_of(AgentId id, double from_s = 0.0) const;
  // Planned restart times of `id`, in order: the launcher's n-th respawn joins at the n-th.
  std::vector<double> restarts_of(AgentId id) const;
  // Whether the plan has `id` running at t_s: not before its late join, not between a kill and
  // its restart, not after a kill without restart.
  bool due_alive(AgentId id, double t_s) const;
  // Whether the plan has brought `id` back by t_s (a late join or a restart that is due): the
  // supervisor must then see it running before it judges the swarm converged.
  bool due_back(AgentId id, double t_s) const;

  // A timed event list for the record: (time, kind, agent, detail).
  struct Event {
    double t_s;
    std::string kind;
    AgentId agent;
    std::string detail;
  };
  std::vector<Event> timeline() const;
};

// A seed for the random stream of one directed link (or any other (a, b) pair a run draws for),
// from the run's seed: independent, reproducible streams.
std::uint64_t link_seed(std::uint64_t seed, AgentId from, AgentId to);

}  // namespace qswarm
