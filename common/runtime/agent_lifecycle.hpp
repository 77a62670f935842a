#pragma once

#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "common/core/topology.hpp"
#include "common/runtime/tick_pacer.hpp"
#include "common/transport/state_message.hpp"

namespace qswarm {

// The phases of one agent process, in order. A late joiner or a restarted agent starts in
// kJoinWait (silent until the swarm's clock reaches its join time); everyone else passes the start
// barrier (Phase::kWaiting until every barrier peer is heard, Phase::kReady until they are all
// ready too).
enum class LifePhase { kJoinWait, kWaiting, kReady, kRunning, kStopping };
const char* to_string(LifePhase p);

struct LifecycleConfig {
  // The peers the start barrier waits for (start_peers(): FIXED-aware, late joiners left out).
  std::set<AgentId> barrier_peers;
  // The start also waits until this many readers matched our state writer (the barrier peers':
  // DDS discovery can lag hearing a peer), and, with a supervisor, until it confirmed hearing our
  // record stream (NeighborBus::recorder_confirmed), so that the recorder sees the start.
  int min_matched_readers = 0;
  bool wait_recorder = false;
  // Late join or restart: wait silently until the swarm's clock reaches this simulated time.
  std::optional<double> join_at_s;
  double time_scale = 1.0;        // simulated seconds per wall second
  double start_timeout_s = 30.0;  // wall: start anyway after this long at the barrier
  double join_timeout_s = 40.0;   // wall: join anyway after this long in kJoinWait
  // wall: how often a ready agent looks whether its peers are ready too (start skew ~ this), and
  // the spacing of its first kReadyAnnouncements ready announcements.
  double announce_period_s = 0.005;
  // wall: announcements otherwise, waiting or ready: a beacon that others are here. Slower than
  // the ready burst for large swarms: N agents waiting for the last replicas to come (compose at 32
  // on two cores), or for the last of 256 to be discovered, would otherwise flood the network and
  // take the CPU they need to discover each other with.
  double waiting_period_s = 0.005;
  double tick_wall_s = 0.02;  // wall seconds per consensus tick
  // Ticks fall on multiples of tick_wall_s on the host's shared time line (Clock::shared_origin_s
  // is where this clock's zero lies on it, less the agent's phase: AgentLoopOptions::tick_phase):
  // the agents of a run that share a phase tick at the same instants, so a process woken by one
  // neighbour's sample finds the others' there too, instead of waking once per sample.
  double tick_origin_s = 0.0;
  double max_wall_s = 150.0;      // wall: stop after running this long
  std::vector<double> kill_at_s;  // planned self-kills (simulated time), ascending
};

// What one peer last said, as the lifecycle needs it.
struct PeerStatus {
  AgentId id = 0;
  Phase phase = Phase::kWaiting;
  double stamp_s = 0.0;
};

// What to do now, decided by AgentLifecycle::step().
struct LifecycleStep {
  std::optional<Phase> announce;  // publish a waiting/ready announcement with this phase
  bool start = false;             // enter Phase::kRunning now, on the swarm clock start_time_s
  double start_time_s = 0.0;
  double swarm_time_s = -1.0;  // kJoinWait: the swarm's clock as the newest running peer says
  int ticks = 0;               // consensus ticks to run now (0 or 1: a late loop catches up)
  bool kill = false;           // a planned kill is due: the process must die now, silently
  bool stop = false;           // the wall limit is reached
  double wake_at_s = 0.0;      // when to call step() next (wall)
  std::string warning;         // something worth a log line (a timeout)
  std::string progress;        // where a long wait stands (every kProgressPeriodS at the barrier)
};

// The agent's phases as one state machine: it takes the wall time, the peers' latest states and the
// agent's simulated time, and says what to publish, how many ticks to run and whether a planned
// kill is due. No clock, no I/O: tests drive it with numbers.
class AgentLifecycle {
 public:
  AgentLifecycle(LifecycleConfig cfg, double now_wall_s);

  LifecycleStep step(double now_wall_s, const std::vector<PeerStatus>& peers, int matched_readers,
                     double agent_time_s, bool recorder_confirmed = true);
  // The process is stopping (a signal, or the wall limit): no more ticks.
  void stop() { phase_ = LifePhase::kStopping; }

  LifePhase phase() const { return phase_; }
  // How often an agent waiting at the start barrier says what it still waits for [wall s].
  static constexpr double kProgressPeriodS = 10.0;
  // Ready announcements at announce_period_s once the agent turns ready, before the slower beacon:
  // a peer learns at once, and one lost datagram costs no more than a period.
  static constexpr int kReadyAnnouncements = 3;
  // Wall seconds from construction to Phase::kRunning (discovery and barrier), -1 before.
  double discovery_s() const { return discovery_s_; }
  const std::optional<TickPacer>& pacer() const { return pacer_; }

 private:
  LifecycleStep join_wait(double now, const std::vector<PeerStatus>& peers);
  LifecycleStep barrier(double now, const std::vector<PeerStatus>& peers, int matched_readers,
                        bool recorder_confirmed);
  LifecycleStep running(double now, double agent_time_s);
  void enter_running(double now, LifecycleStep& s, double start_time_s);

  LifecycleConfig cfg_;
  double born_s_;
  LifePhase phase_;
  double discovery_s_ = -1.0;
  double next_progress_s_ = 0.0;
  // At the barrier: when the next announcement is due (the first one at once), and how many of
  // the fast ready ones are left.
  double next_announce_s_ = -1e300;
  int ready_burst_left_ = 0;
  std::optional<TickPacer> pacer_;
  std::size_t next_kill_ = 0;
};

}  // namespace qswarm
