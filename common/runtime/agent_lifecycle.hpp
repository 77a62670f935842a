#pragma once

#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <utility>
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
  double time_scale = 1.0;  // simulated seconds per wall second
  // The scenario's flight (simulated s; 0: unknown): no running peer's clock is past it.
  double duration_s = 0.0;
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
  // The run's agents, ascending: bit k of the barrier's bitsets is roster[k]. With a roster the
  // start is swarm-wide (AgentLifecycle); empty, an agent runs once its own barrier peers are.
  std::vector<AgentId> roster;
  AgentId self = 0;
  // Where this clock's zero lies on the host's shared time line (Clock::shared_origin_s): the
  // barrier's instants travel on that line.
  double shared_origin_s = 0.0;
};

// What one peer last said, as the lifecycle needs it.
struct PeerStatus {
  PeerStatus() = default;
  PeerStatus(AgentId i, Phase ph, double stamp, std::vector<std::uint8_t> k = {},
             std::vector<std::uint8_t> r = {}, double ready_at = 0.0)
      : id(i),
        phase(ph),
        stamp_s(stamp),
        known(std::move(k)),
        ready(std::move(r)),
        ready_at_s(ready_at) {}
  AgentId id = 0;
  Phase phase = Phase::kWaiting;
  double stamp_s = 0.0;
  std::vector<std::uint8_t> known, ready;  // its barrier bitsets (StateMessage::barrier_*)
  double ready_at_s = 0.0;                 // StateMessage::barrier_ready_at_s
};

// What to do now, decided by AgentLifecycle::step().
struct LifecycleStep {
  std::optional<Phase> announce;  // publish a waiting/ready announcement with this phase
  bool start = false;             // enter Phase::kRunning now, on the swarm clock start_time_s
  // The swarm had been flying for a while when this agent came, and nothing planned it (a pod the
  // cluster restarted, a process started again by hand): it joins on the swarm's clock and asks
  // its neighbours back what it held, as a planned restart does.
  bool late = false;
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
//
// The start is swarm-wide. An agent's barrier peers are only those it hears at the start (its
// neighbourhood, in a large swarm), and releasing each agent once its own peers were ready let a
// large swarm start region by region, as each region finished discovering, each agent's swarm
// clock starting at its own release.
// So each announcement also floods two bitsets over the run's agents, those the sender knows start
// with it (itself, its barrier peers, and what its peers know, transitively) and those it knows
// are ready, with the latest instant (on the host's shared time line) at which one of the ready
// ones turned ready. Every ready bit an agent takes arrives with its sender's known set, so a
// known set that is all ready is closed: it is every agent this one can hear of. Each agent that
// finds it so computes the same go, that last ready instant plus a delay of kGoHops announce
// periods (at most) for the news to spread, and runs then; or at once when a barrier peer already
// runs.
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
  // A running peer's clock this far past the start (wall seconds) makes an agent at the barrier a
  // late one (LifecycleStep::late): further than any agent of one start lags behind its go.
  static constexpr double kLateAfterWallS = 2.0;
  // Ready announcements at announce_period_s once the agent turns ready, before the slower beacon:
  // a peer learns at once, and one lost datagram costs no more than a period.
  static constexpr int kReadyAnnouncements = 3;
  // The go waits this many announce periods (fewer for a smaller swarm) after the last agent
  // turned ready: the hops the news can take to reach every agent before it is due.
  static constexpr std::size_t kGoHops = 32;
  // Wall seconds from construction to Phase::kRunning (discovery and barrier), -1 before.
  double discovery_s() const { return discovery_s_; }
  const std::optional<TickPacer>& pacer() const { return pacer_; }
  // The barrier's bitsets as its announcements carry them (empty without a roster).
  const std::vector<std::uint8_t>& known_bits() const { return known_; }
  const std::vector<std::uint8_t>& ready_bits() const { return ready_; }
  double ready_at_s() const { return ready_at_; }

 private:
  // The swarm's clock as its running peers tell it (t -1: none runs), with a peer stamped far
  // ahead of the others' (upper) median, or past the flight, left out: a stamp from the future
  // moves no agent that joins unless as many peers tell it as the honest ones. `telling`: the
  // running peers within the slack below that clock.
  struct SwarmClock {
    double t = -1.0;
    std::size_t telling = 0;
  };
  SwarmClock swarm_clock(const std::vector<PeerStatus>& peers) const;
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
  double last_announce_s_ = -1e300;
  int ready_burst_left_ = 0;
  std::optional<TickPacer> pacer_;
  std::size_t next_kill_ = 0;
  // The swarm-wide start (see the class comment); sized for the roster.
  std::vector<std::uint8_t> known_, ready_;
  double ready_at_ = 0.0;               // shared time line (every instant on it is positive)
  std::optional<double> own_ready_at_;  // shared time line
  std::optional<double> go_;            // this clock
  // Sets the roster bit of `id` (nothing if it is not in the roster); true if it was clear.
  bool set_bit(std::vector<std::uint8_t>& bits, AgentId id) const;
  // Merges a peer's bitsets, ready instant and phase; true if anything new was learnt.
  bool merge(const PeerStatus& p, double now);
  double go_delay_s() const;
  // Whether every agent known to start is known ready.
  bool all_known_ready() const;
  std::size_t count(const std::vector<std::uint8_t>& bits) const;
};

}  // namespace qswarm
