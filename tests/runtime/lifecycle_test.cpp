// The agent's lifecycle as a state machine: driven with numbers, no clock, no transport; and
// the tick phase it is given, down to two AgentLoops on a manual clock and an in-memory network.
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "common/clock/clock.hpp"
#include "common/runtime/agent_lifecycle.hpp"
#include "common/runtime/agent_loop.hpp"
#include "common/runtime/tick_pacer.hpp"
#include "common/scenario/scenario.hpp"
#include "common/transport/in_memory_bus.hpp"
#include "common/transport/state_message.hpp"
#include "tests/support/plan_for.hpp"

namespace qswarm {
namespace {

LifecycleConfig barrier_config() {
  LifecycleConfig c;
  c.barrier_peers = {2, 3};
  c.start_timeout_s = 30.0;
  c.tick_wall_s = 0.02;
  c.max_wall_s = 100.0;
  return c;
}

TEST(TickPacer, CountsTicksThatStartMoreThanOnePeriodLateAndNeverSkips) {
  TickPacer p(10.0, 0.02);
  EXPECT_DOUBLE_EQ(p.next_due_s(), 10.0);
  p.on_tick(10.001);  // on time
  EXPECT_DOUBLE_EQ(p.next_due_s(), 10.02);
  p.on_tick(10.05);  // 30 ms late: an overrun
  EXPECT_EQ(p.overruns(), 1u);
  EXPECT_TRUE(p.due(10.05));  // the loop catches up without sleeping
  p.on_tick(10.05);           // due 10.04, 10 ms late: not an overrun
  EXPECT_EQ(p.overruns(), 1u);
  EXPECT_EQ(p.ticks(), 3u);
  EXPECT_THROW(TickPacer(0.0, 0.0), std::invalid_argument);
}

TEST(Lifecycle, BarrierWaitsForEveryPeerThenForEveryoneReady) {
  // Given an agent that waits for peers 2 and 3
  AgentLifecycle life(barrier_config(), 0.0);
  // When it has heard only 2, it announces Phase::kWaiting every 5 ms
  LifecycleStep s = life.step(0.0, {{2, Phase::kWaiting, 0.0}}, 0, 0.0);
  EXPECT_EQ(life.phase(), LifePhase::kWaiting);
  ASSERT_TRUE(s.announce);
  EXPECT_EQ(*s.announce, Phase::kWaiting);
  EXPECT_DOUBLE_EQ(s.wake_at_s, 0.005);
  // Once it hears both it is ready, but runs only once both are ready too
  s = life.step(0.005, {{2, Phase::kWaiting, 0.0}, {3, Phase::kWaiting, 0.0}}, 0, 0.0);
  EXPECT_EQ(life.phase(), LifePhase::kReady);
  EXPECT_EQ(*s.announce, Phase::kReady);
  EXPECT_FALSE(s.start);
  // A stranger being ready changes nothing
  s = life.step(
      0.010, {{2, Phase::kReady, 0.0}, {3, Phase::kWaiting, 0.0}, {9, Phase::kReady, 0.0}}, 0, 0.0);
  EXPECT_FALSE(s.start);
  s = life.step(0.015, {{2, Phase::kReady, 0.0}, {3, Phase::kRunning, 0.0}}, 0, 0.0);
  EXPECT_TRUE(s.start);
  EXPECT_DOUBLE_EQ(s.start_time_s, 0.0);
  EXPECT_EQ(life.phase(), LifePhase::kRunning);
  EXPECT_DOUBLE_EQ(life.discovery_s(), 0.015);
}

TEST(Lifecycle, WaitingForMissingPeersIsABeaconAndReadyIsFast) {
  // A large swarm: waiting for peers that are not there yet (replicas still claiming ids) announces
  // slowly; once all are heard, the ready announcements keep the start skew small.
  LifecycleConfig c = barrier_config();
  c.waiting_period_s = 0.2;
  c.announce_period_s = 0.02;
  AgentLifecycle life(c, 0.0);
  LifecycleStep s = life.step(0.0, {{2, Phase::kWaiting, 0.0}}, 0, 0.0);
  EXPECT_EQ(*s.announce, Phase::kWaiting);
  EXPECT_DOUBLE_EQ(s.wake_at_s, 0.2);
  s = life.step(0.2, {{2, Phase::kWaiting, 0.0}, {3, Phase::kWaiting, 0.0}}, 0, 0.0);
  EXPECT_EQ(*s.announce, Phase::kReady);
  EXPECT_DOUBLE_EQ(s.wake_at_s, 0.22);
}

TEST(Lifecycle, AnAgentPolledOftenAtTheBarrierAnnouncesOnlyWhenDue) {
  // The process polls every 10 ms (it must see a stop request); the periods are a large swarm's.
  LifecycleConfig c = barrier_config();
  c.waiting_period_s = 0.2;
  c.announce_period_s = 0.02;
  AgentLifecycle life(c, 0.0);
  const auto announcements = [&](int from, int to, const std::vector<PeerStatus>& peers) {
    int n = 0;
    for (int i = from; i < to; ++i) {
      const LifecycleStep s = life.step(0.01 * i, peers, 0, 0.0);
      EXPECT_FALSE(s.start);
      if (s.announce) ++n;
    }
    return n;
  };
  // Waiting for peer 3 for a second: a beacon every 0.2 s, not one per poll
  EXPECT_EQ(announcements(0, 100, {{2, Phase::kWaiting, 0.0}}), 5);
  EXPECT_EQ(life.phase(), LifePhase::kWaiting);
  // Ready (and still waiting for them to be) for a second: at once, twice more 20 ms apart, then
  // the beacon again
  EXPECT_EQ(announcements(100, 200, {{2, Phase::kWaiting, 0.0}, {3, Phase::kWaiting, 0.0}}), 7);
  EXPECT_EQ(life.phase(), LifePhase::kReady);
  // Its poll stays fast: it starts within one announce period of its peers being ready
  const LifecycleStep s =
      life.step(2.0, {{2, Phase::kReady, 0.0}, {3, Phase::kWaiting, 0.0}}, 0, 0.0);
  EXPECT_NEAR(s.wake_at_s, 2.02, 1e-9);
  EXPECT_TRUE(life.step(2.02, {{2, Phase::kReady, 0.0}, {3, Phase::kReady, 0.0}}, 0, 0.0).start);
}

TEST(Lifecycle, TheBarrierWaitsForItsPeersReadersAndTheSupervisorsRecordReader) {
  LifecycleConfig c = barrier_config();
  c.min_matched_readers = 2;  // peers 2 and 3
  c.wait_recorder = true;
  AgentLifecycle life(c, 0.0);
  const std::vector<PeerStatus> ready = {{2, Phase::kReady, 0.0}, {3, Phase::kReady, 0.0}};
  EXPECT_FALSE(life.step(0.0, ready, 1, 0.0, true).start);     // one peer's reader missing
  EXPECT_FALSE(life.step(0.005, ready, 2, 0.0, false).start);  // no recorder yet
  EXPECT_EQ(life.phase(), LifePhase::kWaiting);
  EXPECT_TRUE(life.step(0.01, ready, 2, 0.0, true).start);
}

// Agents 1..n in a line, each hearing only its neighbours at the start, stepped in rounds of one
// announce period: each hears what its neighbours last announced. The last agent hears its
// neighbour (is discovered) only from `discovered_s`. Returns each agent's start instant.
std::vector<double> line_start(int n, bool swarm_wide, double discovered_s) {
  std::vector<AgentLifecycle> lives;
  std::vector<PeerStatus> said(n + 1);  // by id: the last announcement
  for (int id = 1; id <= n; ++id) {
    LifecycleConfig c = barrier_config();
    c.barrier_peers.clear();
    for (const int p : {id - 1, id + 1})
      if (p >= 1 && p <= n) c.barrier_peers.insert(static_cast<AgentId>(p));
    if (swarm_wide)
      for (int a = 1; a <= n; ++a) c.roster.push_back(static_cast<AgentId>(a));
    c.self = static_cast<AgentId>(id);
    c.shared_origin_s = 100.0;  // the host's time line lies elsewhere than this clock's zero
    lives.emplace_back(c, 0.0);
    said[id] = PeerStatus(static_cast<AgentId>(id), Phase::kWaiting, 0.0);
  }
  std::vector<double> started(n, -1.0);
  for (double t = 0.0; t < 5.0; t += 0.005) {
    std::vector<PeerStatus> next = said;
    for (int id = 1; id <= n; ++id) {
      AgentLifecycle& life = lives[id - 1];
      if (life.phase() == LifePhase::kRunning) continue;
      std::vector<PeerStatus> heard;
      for (const int p : {id - 1, id + 1}) {
        const bool late_link = (id == n && p == n - 1) || (id == n - 1 && p == n);
        if (p >= 1 && p <= n && (!late_link || t >= discovered_s)) heard.push_back(said[p]);
      }
      const LifecycleStep s = life.step(t, heard, 1, 0.0);
      if (s.start) {
        started[id - 1] = t;
        next[id].phase = Phase::kRunning;
      } else if (s.announce) {
        next[id] = PeerStatus(static_cast<AgentId>(id), *s.announce, 0.0, life.known_bits(),
                              life.ready_bits(), life.ready_at_s());
      }
    }
    said = std::move(next);
  }
  return started;
}

TEST(Lifecycle, ASwarmStartsTogetherAtItsLastAgentsReadinessNotRegionByRegion) {
  // Given six agents in a line whose last one is discovered only after 1 s
  // When each starts once its own neighbours are ready (no roster: the old rule)
  const std::vector<double> local = line_start(6, false, 1.0);
  // Then the first three start at once, a second before the others
  EXPECT_LT(local[0], 0.05);
  EXPECT_GT(local[5], 1.0);
  // When the barrier floods who is ready over the run's agents
  const std::vector<double> wide = line_start(6, true, 1.0);
  // Then all six start at the same instant: the last readiness (1.0 s, when the last pair
  // heard each other) plus the go delay (6 agents' announce periods), whatever its hops
  for (const double t : wide) {
    EXPECT_NEAR(t, wide[0], 1e-9);
    EXPECT_GE(t, 1.0 + 6 * 0.005 - 1e-9);
    EXPECT_LT(t, 1.0 + 6 * 0.005 + 0.011);
  }
}

TEST(Lifecycle, AnyRunningAgentOfTheRunReleasesAnAgentWhosePeersAreReady) {
  // Given agent 1, whose start peer 2 is ready, and agent 3 it heard but still thinks waiting
  LifecycleConfig c = barrier_config();
  c.barrier_peers = {2};
  c.roster = {1, 2, 3};
  c.self = 1;
  AgentLifecycle life(c, 0.0);
  LifecycleStep s = life.step(0.0, {{2, Phase::kReady, 0.0}, {3, Phase::kWaiting, 0.0}}, 1, 0.0);
  EXPECT_FALSE(s.start);
  // When agent 3 runs (it started at its go; running, it sends no bitsets)
  s = life.step(0.005, {{2, Phase::kReady, 0.0}, {3, Phase::kRunning, 0.0}}, 1, 0.0);
  // Then agent 1 runs too, without waiting for its timeout
  EXPECT_TRUE(s.start);
}

TEST(Lifecycle, AnAgentThatFindsTheSwarmLongInFlightJoinsOnItsClockAsARestartWould) {
  // Given an agent born at the barrier (nothing planned its late start: a pod the cluster
  // restarted) whose peers have flown 30 s
  AgentLifecycle late(barrier_config(), 100.0);
  // A lone running sample (one peer of two; a forger's would look the same) releases nothing
  LifecycleStep s = late.step(100.0, {{2, Phase::kRunning, 30.0}}, 0, 0.0);
  EXPECT_FALSE(s.start);
  // Two peers telling the same clock: it joins at once, on the swarm's clock, as late (it asks
  // back what it held)
  s = late.step(100.01, {{2, Phase::kRunning, 30.0}, {3, Phase::kRunning, 30.02}}, 0, 0.0);
  EXPECT_TRUE(s.start);
  EXPECT_TRUE(s.late);
  EXPECT_DOUBLE_EQ(s.start_time_s, 30.02);
  EXPECT_EQ(late.phase(), LifePhase::kRunning);
  // Given a peer that started a moment before this agent's own go (1.5 wall s at time scale 4)
  LifecycleConfig c = barrier_config();
  c.time_scale = 4.0;
  AgentLifecycle slow(c, 0.0);
  s = slow.step(0.0, {{2, Phase::kRunning, 6.0}}, 1, 0.0);
  // Then it is no late joiner: it waits for its barrier as usual
  EXPECT_FALSE(s.start);
  EXPECT_FALSE(s.late);
  s = slow.step(0.1, {{2, Phase::kRunning, 6.4}, {3, Phase::kRunning, 6.4}}, 1, 0.0);
  EXPECT_TRUE(s.start);
  EXPECT_FALSE(s.late);
  EXPECT_DOUBLE_EQ(s.start_time_s, 0.0);
}

TEST(Lifecycle, AClaimedReadinessInTheFutureCannotHoldTheStartBack) {
  // Given an agent whose only peer claims everyone turned ready a thousand seconds from now
  LifecycleConfig c = barrier_config();
  c.barrier_peers = {2};
  c.roster = {1, 2};
  c.self = 1;
  AgentLifecycle life(c, 0.0);
  const std::vector<std::uint8_t> both = {0b11};
  LifecycleStep s = life.step(0.0, {{2, Phase::kReady, 0.0, both, both, 1000.0}}, 1, 0.0);
  EXPECT_FALSE(s.start);
  // Then the claim counts as now: the start is the go delay later (two announce periods)
  EXPECT_NEAR(life.ready_at_s(), 0.0, 1e-12);
  s = life.step(0.010, {{2, Phase::kReady, 0.0, both, both, 1000.0}}, 1, 0.0);
  EXPECT_TRUE(s.start);
  // And bitsets of another length (another roster) are not read: agent 3 of a larger one is not
  // awaited, and nothing there counts as ready
  AgentLifecycle other(c, 0.0);
  s = other.step(0.0, {{2, Phase::kWaiting, 0.0, {0xff, 0xff}, {0xff, 0xff}, 0.0}}, 1, 0.0);
  EXPECT_EQ(other.known_bits(), std::vector<std::uint8_t>{0b11});
  EXPECT_EQ(other.ready_bits(), std::vector<std::uint8_t>{0b01});  // itself only
}

TEST(Lifecycle, StartsAnywayAfterTheStartTimeoutAndSaysSo) {
  AgentLifecycle life(barrier_config(), 0.0);
  EXPECT_FALSE(life.step(29.9, {{2, Phase::kReady, 0.0}}, 0, 0.0).start);
  const LifecycleStep s = life.step(30.1, {{2, Phase::kReady, 0.0}}, 0, 0.0);
  EXPECT_TRUE(s.start);
  EXPECT_NE(s.warning.find("1 of 2 peers ready"), std::string::npos) << s.warning;
}

TEST(Lifecycle, RunningPacesOneTickPerPeriodAndCountsLateTicks) {
  LifecycleConfig c = barrier_config();
  c.barrier_peers = {};
  AgentLifecycle life(c, 0.0);
  ASSERT_TRUE(life.step(1.0, {}, 0, 0.0).start);
  LifecycleStep s = life.step(1.0, {}, 0, 0.0);
  EXPECT_EQ(s.ticks, 1);
  EXPECT_DOUBLE_EQ(s.wake_at_s, 1.02);
  s = life.step(1.01, {}, 0, 0.02);  // woken early: nothing due
  EXPECT_EQ(s.ticks, 0);
  s = life.step(1.07, {}, 0, 0.02);  // 50 ms late
  EXPECT_EQ(s.ticks, 1);
  EXPECT_EQ(life.pacer()->overruns(), 1u);
  EXPECT_DOUBLE_EQ(s.wake_at_s, 1.04);  // catches up at once
}

TEST(Lifecycle, TicksFallOnTheHostsSharedGridSoAgentsTickTogether) {
  // Given two agents whose clocks started at different instants of the host's time line
  LifecycleConfig a = barrier_config(), b = barrier_config();
  a.barrier_peers = b.barrier_peers = {};
  a.tick_origin_s = 100.013;  // clock a read 0 at 100.013 s on the shared line
  b.tick_origin_s = 100.0;
  AgentLifecycle la(a, 0.0), lb(b, 0.0);
  // When they start running at different moments
  ASSERT_TRUE(la.step(0.5, {}, 0, 0.0).start);
  ASSERT_TRUE(lb.step(0.531, {}, 0, 0.0).start);
  // Then each first tick is the next multiple of the period on the shared line, the same instant
  // for both: 100.52 (a: 0.507 on its clock) and 100.54 (b: 0.54)
  EXPECT_NEAR(la.pacer()->next_due_s() + a.tick_origin_s, 100.52, 1e-9);
  EXPECT_NEAR(lb.pacer()->next_due_s() + b.tick_origin_s, 100.54, 1e-9);
  EXPECT_EQ(la.step(0.5, {}, 0, 0.0).ticks, 0);  // not before the grid
  const LifecycleStep s = la.step(0.507, {}, 0, 0.0);
  EXPECT_EQ(s.ticks, 1);
  EXPECT_NEAR(s.wake_at_s + a.tick_origin_s, 100.54, 1e-9);
}

std::set<AgentId> ids_from(AgentId first, AgentId step, int n) {
  std::set<AgentId> ids;
  for (int k = 0; k < n; ++k) ids.insert(first + step * static_cast<AgentId>(k));
  return ids;
}

TEST(TickPhase, PastSixteenAgentsEverySecondOneTicksHalfAPeriodLate) {
  const std::set<AgentId> swarm = ids_from(1, 1, 32);  // 1 .. 32
  const RunPlan plan = test::plan_for(32);
  EXPECT_EQ(plan.tick_phase(swarm, 1), 0.0);
  EXPECT_EQ(plan.tick_phase(swarm, 2), 0.5);
  EXPECT_EQ(plan.tick_phase(swarm, 32), 0.5);
  EXPECT_EQ(plan.tick_phase(swarm, 33), 0.0);  // not in the swarm
  EXPECT_EQ(test::plan_for(17).tick_phase(ids_from(1, 1, 17), 2), 0.5);
  // a burst of a few agents passes at once
  EXPECT_EQ(test::plan_for(16).tick_phase(ids_from(1, 1, 16), 2), 0.0);
  // By order, not by id: a swarm of even ids still splits in half
  const std::set<AgentId> even = ids_from(2, 2, 20);  // 2, 4 .. 40
  int late = 0;
  for (const AgentId id : even) late += test::plan_for(20).tick_phase(even, id) > 0.0 ? 1 : 0;
  EXPECT_EQ(late, 10);
}

TEST(TickPhase, AnAgentLoopTicksAtItsPhaseOfTheSharedGrid) {
  // Given the two agents of a run on one clock, agent 2 told to tick at half a period
  const RunConfig rc = resolve_scenario(parse_scenario_text(
      "agents { id: 1 position { x: 0 y: 0 z: 10 } }\n"
      "agents { id: 2 position { x: 2 y: 0 z: 10 } }\n"
      "weight { policy: UNWEIGHTED } topology { policy: PROXIMITY threshold_m: 100 }\n",
      "two"));
  InMemoryNetwork net;
  InMemoryBus bus1(net), bus2(net);
  ManualClock clock;
  AgentLoopOptions late;
  late.tick_phase = 0.5;
  AgentLoop a1(rc, 1, AgentLoopOptions{}, bus1, clock), a2(rc, 2, late, bus2, clock);
  // When both pass the barrier and tick a while
  double wake1 = 0.0, wake2 = 0.0;
  for (int k = 0; k < 100000 && (a1.ticks() < 10 || a2.ticks() < 10); ++k) {
    if (wake1 <= clock.now_s()) wake1 = a1.poll().wake_at_s;
    if (wake2 <= clock.now_s()) wake2 = a2.poll().wake_at_s;
    net.deliver();
    clock.sleep_until(std::min(wake1, wake2));
  }
  // Then agent 1 ticks on multiples of the period (its clock's zero is the grid's), and agent 2
  // half a period after them
  ASSERT_GE(a2.ticks(), 10u);
  const double period = rc.agent.steps_per_tick() / rc.agent.physics_hz;
  const auto phase = [&](double t) { return std::remainder(t / period, 1.0); };
  EXPECT_NEAR(phase(a1.running_since_s()), 0.0, 1e-9);
  EXPECT_NEAR(std::abs(phase(a2.running_since_s())), 0.5, 1e-9);
  EXPECT_NEAR(std::abs(phase(wake2)), 0.5, 1e-9);
  a1.stop();
  a2.stop();
}

TEST(Lifecycle, APlannedKillIsDueAtItsSimulatedTimeAndNotBefore) {
  LifecycleConfig c = barrier_config();
  c.barrier_peers = {};
  c.kill_at_s = {0.5};
  AgentLifecycle life(c, 0.0);
  ASSERT_TRUE(life.step(0.0, {}, 0, 0.0).start);
  EXPECT_FALSE(life.step(0.48, {}, 0, 0.48).kill);
  EXPECT_TRUE(life.step(0.50, {}, 0, 0.50).kill);
}

TEST(Lifecycle, ALateJoinerStaysSilentUntilTheSwarmClockReachesItsTime) {
  LifecycleConfig c = barrier_config();
  c.join_at_s = 3.0;
  c.kill_at_s = {1.0, 6.0};  // the kill at 1 s was a predecessor's
  AgentLifecycle life(c, 0.0);
  EXPECT_EQ(life.phase(), LifePhase::kJoinWait);
  LifecycleStep s = life.step(0.1, {{2, Phase::kRunning, 2.5}, {3, Phase::kWaiting, 9.0}}, 0, 0.0);
  EXPECT_FALSE(s.announce);  // silent
  EXPECT_FALSE(s.start);
  EXPECT_DOUBLE_EQ(s.swarm_time_s, 2.5);  // only running peers' stamps count
  s = life.step(0.2, {{2, Phase::kRunning, 3.02}}, 0, 0.0);
  EXPECT_TRUE(s.start);
  EXPECT_DOUBLE_EQ(s.start_time_s, 3.02);
  EXPECT_FALSE(life.step(0.2, {}, 0, 3.02).kill);
  EXPECT_TRUE(life.step(3.2, {}, 0, 6.0).kill);
}

// A planned late joiner (or a restart) due at join_at_s, in a 60 s flight.
LifecycleConfig joining_at(double join_at_s) {
  LifecycleConfig c = barrier_config();
  c.join_at_s = join_at_s;
  c.duration_s = 60.0;
  return c;
}

TEST(Lifecycle, ALateJoinerIsNotMovedByOnePeersStampFromTheFuture) {
  // A planned late joiner (at 3 s) hears two honest peers near 3 s and one stamped a million
  // seconds ahead (a forger's, or a relay's from the future): it joins on the honest clock.
  AgentLifecycle life(joining_at(3.0), 0.0);
  LifecycleStep s = life.step(
      0.1, {{2, Phase::kRunning, 3.1}, {3, Phase::kRunning, 3.2}, {4, Phase::kRunning, 1e6}}, 0,
      0.0);
  EXPECT_TRUE(s.start);
  EXPECT_DOUBLE_EQ(s.start_time_s, 3.2);
  // Ahead of the others by more than the slack, even within the flight: left out too.
  AgentLifecycle ahead(joining_at(3.0), 0.0);
  s = ahead.step(0.1,
                 {{2, Phase::kRunning, 3.1}, {3, Phase::kRunning, 3.2}, {4, Phase::kRunning, 40.0}},
                 0, 0.0);
  EXPECT_DOUBLE_EQ(s.start_time_s, 3.2);
}

TEST(Lifecycle, AnAgentWhoseOnlyRunningPeerIsStampedFromTheFutureDoesNotJoinOnIt) {
  // Its one running neighbour claims a clock past the whole flight (60 s): no swarm runs there.
  LifecycleConfig c = barrier_config();
  c.duration_s = 60.0;
  AgentLifecycle late(c, 0.0);
  LifecycleStep s = late.step(0.0, {{2, Phase::kRunning, 1e6}}, 0, 0.0);
  EXPECT_FALSE(s.start);
  EXPECT_FALSE(s.late);
  AgentLifecycle joiner(joining_at(3.0), 0.0);
  s = joiner.step(0.1, {{2, Phase::kRunning, 1e6}}, 0, 0.0);
  EXPECT_FALSE(s.start);
  EXPECT_DOUBLE_EQ(s.swarm_time_s, -1.0);
  // An honest peer at 3.05 s: the joiner starts there.
  s = joiner.step(0.2, {{2, Phase::kRunning, 1e6}, {3, Phase::kRunning, 3.05}}, 0, 0.0);
  EXPECT_TRUE(s.start);
  EXPECT_DOUBLE_EQ(s.start_time_s, 3.05);
}

TEST(Lifecycle, AJoinerTakesTheLiveClockOverADeadPeersLastStamp) {
  // A restart due at 12 s hears agent 2's last stamp (4 s: it was killed without a word, and its
  // last sample stays) beside agent 3's live clock: the live one counts.
  AgentLifecycle life(joining_at(12.0), 0.0);
  LifecycleStep s = life.step(7.0, {{2, Phase::kRunning, 4.0}, {3, Phase::kRunning, 9.0}}, 0, 0.0);
  EXPECT_FALSE(s.start);
  EXPECT_DOUBLE_EQ(s.swarm_time_s, 9.0);
  s = life.step(10.0, {{2, Phase::kRunning, 4.0}, {3, Phase::kRunning, 12.02}}, 0, 0.0);
  EXPECT_TRUE(s.start);
  EXPECT_DOUBLE_EQ(s.start_time_s, 12.02);
}

TEST(Lifecycle, AJoinerWhoseSwarmNeverRunsJoinsAfterItsTimeoutAndSaysSo) {
  LifecycleConfig c = barrier_config();
  c.join_at_s = 2.0;
  c.join_timeout_s = 5.0;
  AgentLifecycle life(c, 0.0);
  EXPECT_FALSE(life.step(6.9, {}, 0, 0.0).start);
  const LifecycleStep s = life.step(7.1, {}, 0, 0.0);
  EXPECT_TRUE(s.start);
  EXPECT_DOUBLE_EQ(s.start_time_s, 0.0);
  EXPECT_NE(s.warning.find("never reached"), std::string::npos);
}

TEST(Lifecycle, StopsAtTheWallLimit) {
  LifecycleConfig c = barrier_config();
  c.barrier_peers = {};
  c.max_wall_s = 1.0;
  AgentLifecycle life(c, 0.0);
  ASSERT_TRUE(life.step(0.0, {}, 0, 0.0).start);
  EXPECT_FALSE(life.step(0.9, {}, 0, 0.9).stop);
  EXPECT_TRUE(life.step(1.1, {}, 0, 1.1).stop);
  EXPECT_EQ(life.phase(), LifePhase::kStopping);
}

}  // namespace
}  // namespace qswarm
