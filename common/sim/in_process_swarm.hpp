#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/clock/clock.hpp"
#include "common/core/graph.hpp"
#include "common/record/supervisor_loop.hpp"
#include "common/runtime/agent_loop.hpp"
#include "common/runtime/restart_policy.hpp"
#include "common/scenario/run_config.hpp"
#include "common/sim/liar.hpp"
#include "common/transport/in_memory_bus.hpp"

namespace qswarm {

// A whole run in one process: one AgentLoop per agent of the RunConfig (the object swarm-agent
// runs), each on its own endpoint of an InMemoryNetwork, all on one ManualClock. Like `swarm run`
// it starts every agent at once (late joiners wait silently), and respawns an agent killed by the
// plan under the same RestartPolicy. Given a run directory, it also records the run with the
// supervisor's own loop on another endpoint (which only listens), so the run ends with the real
// convergence judgement and summary. Deterministic: agents are polled in id order and a round's
// messages are delivered after the round.
class InProcessSwarm {
 public:
  explicit InProcessSwarm(RunConfig rc, double time_scale = 1.0, RunDir record_in = {});
  ~InProcessSwarm();

  // One round: poll every agent that is due, deliver, move the clock to the next wake-up.
  void step();
  // Steps until the wall clock (time-scaled seconds since the start) reaches wall_s.
  void run_until_wall(double wall_s);
  // Steps until pred() holds or the wall clock passes max_wall_s; returns whether pred held.
  bool run_until(const std::function<bool()>& pred, double max_wall_s);
  // With a run directory: steps until the supervisor ends the run (or the wall clock passes
  // max_wall_s: "interrupted"), stops every agent and writes the record. Returns the end reason;
  // supervisor()->exit_code() is what swarm-supervisor would exit with.
  std::string run_recorded(double max_wall_s);
  const SupervisorLoop* supervisor() const { return supervisor_.get(); }
  // The agent's process dies unplanned (a crash, a SIGKILL from outside): silently, and the
  // restart policy does not bring it back.
  void crash(AgentId id);
  // From now on agent liar.id lies (each call adds a liar): every consensus state it sends, to its
  // neighbours and to the recorder, is liar.claim(receiver, its q0, its stamp) (the recorder counts
  // as id 0), and a point agent's position with it. It still runs the real runtime; only what it
  // says changes.
  void add_liar(const Liar& liar);

  double wall_s() const { return clock_.now_s(); }
  const RunConfig& config() const { return rc_; }
  // The agent's current life, or nullptr while it is dead.
  const AgentLoop* agent(AgentId id) const;
  // Consensus states of the agents alive and running, in id order.
  Positions running_states() const;
  // Largest distance of a running agent's consensus state from their mean (0 if none).
  double disagreement_running() const;
  // Notes the agents logged, kills and respawns, in order: "wall_s agent text".
  const std::vector<std::string>& log() const { return log_; }
  // The network, for tests that act as a stranger on it.
  InMemoryNetwork& network() { return net_; }

 private:
  struct Slot {
    std::unique_ptr<InMemoryBus> bus;
    std::unique_ptr<AgentLoop> loop;
    double wake_at_s = 0.0;
    int life = 0;
    bool finished = false;
  };
  void spawn(AgentId id, Slot& slot, std::optional<double> join_at_s);
  void note(AgentId id, const std::string& text);

  RunConfig rc_;
  double time_scale_;
  ManualClock clock_;
  InMemoryNetwork net_;
  RestartPolicy restarts_;
  std::map<AgentId, Slot> slots_;
  std::vector<std::string> log_;
  // The recorder's endpoint and loop (with a run directory).
  std::unique_ptr<InMemoryBus> supervisor_bus_;
  std::unique_ptr<SupervisorLoop> supervisor_;
  double supervisor_wake_s_ = 0.0;
  std::optional<std::string> end_reason_;
  std::vector<Liar> liars_;
};

}  // namespace qswarm
