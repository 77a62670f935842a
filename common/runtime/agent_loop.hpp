#pragma once

#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "common/clock/clock.hpp"
#include "common/runtime/agent_lifecycle.hpp"
#include "common/runtime/agent_runtime.hpp"
#include "common/runtime/faulty_bus.hpp"
#include "common/runtime/neighbourhood.hpp"
#include "common/scenario/run_config.hpp"

namespace qswarm {

// How this process of the agent was started (the swarm-agent flags beyond the scenario).
struct AgentLoopOptions {
  double time_scale = 1.0;  // simulated seconds per wall second
  // Wall seconds at the start barrier before starting anyway (-1: RunPlan::start_timeout_s).
  double start_timeout_s = -1.0;
  double max_wall_s = -1.0;      // wall limit once running (default 2 x duration + 30 s)
  double join_at_s = -1.0;       // join on the swarm's clock at this time (-1: the plan's)
  bool restarted = false;        // recover the flows this agent owned from its neighbours
  bool wait_supervisor = false;  // the barrier also waits for the supervisor's reader
  std::int64_t incarnation = 0;  // this life's identity (the process uses its start time)
  // Where in each tick period of the host's shared grid this agent ticks, as a fraction of the
  // period (RunPlan::tick_phase; the in-process swarm ticks every agent at 0).
  double tick_phase = 0.0;
  std::string host;  // where this process flies, "NAME/ADDRESS" (StateMessage::host)
};

// One agent as the product runs it: its lifecycle (join wait, barrier, paced ticks, planned kills)
// over a transport, the fault-injecting decorator, and the AgentRuntime (dynamics, control, law).
// swarm-agent polls it on a SteadyClock over DDS; the in-process swarm polls the same object on a
// ManualClock over the in-memory network. No I/O: what is worth logging comes back as notes.
class AgentLoop {
 public:
  AgentLoop(const RunConfig& rc, AgentId id, const AgentLoopOptions& opts, NeighborBus& transport,
            Clock& clock);
  // What the agent hears now (its neighbourhood's interest, last told to the transport).
  const Interest& interest() const { return interest_; }
  // How often its interest moved (each move makes DDS re-match its endpoints with every peer).
  std::uint64_t interest_changes() const { return interest_changes_; }

  struct Note {
    bool warning = false;
    std::string text;
  };
  struct Poll {
    std::vector<Note> notes;
    bool kill = false;  // a planned kill is due: the process must die now (SIGKILL)
    bool done = false;  // the wall limit is reached: stop
    double wake_at_s = 0.0;
  };
  // Reads the clock and the transport, advances the lifecycle, runs what is due.
  Poll poll();
  // Announce Phase::kStopping (a signal or the end); no more ticks.
  void stop();

  LifePhase phase() const { return life_.phase(); }
  const AgentRuntime& runtime() const { return runtime_; }
  const AgentLifecycle& lifecycle() const { return life_; }
  BusCounters transport_counters() const { return transport_.counters(); }
  FaultCounters fault_counters() const { return faulty_.fault_counters(); }
  std::uint64_t physics_steps() const { return physics_steps_; }
  std::uint64_t ticks() const;
  std::uint64_t overruns() const;
  // Wall time when the law started running (-1 before).
  double running_since_s() const;

 private:
  void update_interest();
  AgentId id_;
  std::function<bool(AgentId)> is_agent_;
  Clock& clock_;
  NeighborBus& transport_;
  FaultyBus faulty_;
  AgentRuntime runtime_;
  AgentLifecycle life_;
  Neighbourhood neighbourhood_;
  Interest interest_;  // what the transport was last told
  bool interest_told_ = false;
  std::uint64_t interest_changes_ = 0;
  std::uint64_t physics_steps_ = 0;
  // Wall seconds between two records in flight, and when an announcement last went to the recorder.
  double record_period_wall_s_ = 0.0;
  double last_announce_record_s_ = 0.0;
};

}  // namespace qswarm
