// The agent's runtime as its process drives it: what a sample carries when it is handed over.
#include <gtest/gtest.h>

#include <vector>

#include "common/clock/clock.hpp"
#include "common/runtime/agent_runtime.hpp"
#include "common/scenario/scenario.hpp"
#include "common/transport/neighbor_bus.hpp"

namespace qswarm {
namespace {

// A transport that keeps, with every sample handed to it, the clock's wall time at that moment;
// reading the neighbours takes 1 ms of it, and a state sample's send 2 ms (a slow sendto).
class StampCheckingBus final : public NeighborBus {
 public:
  explicit StampCheckingBus(ManualClock& clock) : clock_(clock) {}
  struct Handed {
    std::int64_t carried, at;
  };
  std::vector<Handed> published, recorded;

  void publish(const StateMessage& m) override {
    published.push_back({m.wall_ns, clock_.wall_ns()});
    clock_.advance(0.002);
  }
  void record(const StateMessage& m) override { recorded.push_back({m.wall_ns, clock_.wall_ns()}); }
  void for_each_latest(AgentId, const std::function<void(const StateMessage&)>&) override {
    clock_.advance(0.001);
  }
  void set_listener(Listener) override {}
  BusCounters counters() const override { return {}; }

 private:
  ManualClock& clock_;
};

AgentParams lone_agent() {
  const RunConfig rc =
      resolve_scenario(parse_scenario_text("agents { id: 1 position { x: 0 y: 0 z: 10 } }\n"
                                           "rates { physics_hz: 500 consensus_hz: 50 }\n",
                                           "lone"));
  return AgentParams{*rc.spec(1), rc.agent, {}};
}

TEST(AgentRuntime, ASampleCarriesTheWallTimeAtWhichItIsHandedOverNotTheTicksStart) {
  // Given an agent whose clock moves while it reads its neighbours and while it sends
  ManualClock clock;
  StampCheckingBus bus(clock);
  AgentRuntime a(lone_agent(), bus);
  a.set_wall_clock(&clock);
  // When it flies three consensus ticks of ten steps each
  const std::int64_t start = clock.wall_ns();
  for (int i = 0; i < 30; ++i) (void)a.step();
  // Then every state sample carries the time it was handed over, after the tick read its
  // neighbours, and the record (sent after it) the time it was handed over in turn
  ASSERT_EQ(bus.published.size(), 3u);
  ASSERT_EQ(bus.recorded.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(bus.published[k].carried, bus.published[k].at);
    EXPECT_EQ(bus.recorded[k].carried, bus.recorded[k].at);
    EXPECT_EQ(bus.recorded[k].carried - bus.published[k].carried, 2'000'000);
  }
  EXPECT_GE(bus.published[0].carried - start, 1'000'000);
}

TEST(AgentRuntime, WithoutAWallClockASampleCarriesNone) {
  ManualClock clock;
  StampCheckingBus bus(clock);
  AgentRuntime a(lone_agent(), bus);
  a.publish(Phase::kWaiting);
  ASSERT_EQ(bus.published.size(), 1u);
  EXPECT_EQ(bus.published.front().carried, 0);
}

// A transport that keeps which of the agent's ticks went to the recorder.
class RecordedTicksBus final : public NeighborBus {
 public:
  std::vector<int> recorded_ticks;
  void publish(const StateMessage& m) override { ticks += m.phase == Phase::kRunning ? 1 : 0; }
  void record(const StateMessage& m) override {
    if (m.phase == Phase::kRunning) recorded_ticks.push_back(ticks);
  }
  void for_each_latest(AgentId, const std::function<void(const StateMessage&)>&) override {}
  void set_listener(Listener) override {}
  BusCounters counters() const override { return {}; }

 private:
  int ticks = 0;
};

// The ticks (counted from 1) that agent `id` records in its first 16, after `announcements` at its
// start barrier, with one record every 5 ticks.
std::vector<int> recorded_ticks(AgentId id, int announcements, bool spread) {
  AgentParams p = lone_agent();
  p.spec.id = id;
  p.start.record_every = 5;
  p.start.spread_records = spread;
  RecordedTicksBus bus;
  AgentRuntime a(p, bus);
  for (int i = 0; i < announcements; ++i) (void)a.publish(Phase::kReady);
  for (int i = 0; i < 16 * 10; ++i) (void)a.step();
  return bus.recorded_ticks;
}

TEST(AgentRuntime, AgentsRecordTheSameTicksHoweverManyAnnouncementsTheyMade) {
  for (const AgentId id : {1u, 2u, 7u})
    for (const int announcements : {0, 1, 3, 4, 12})
      EXPECT_EQ(recorded_ticks(id, announcements, false), (std::vector<int>{5, 10, 15}))
          << "agent " << id << " after " << announcements << " announcements";
}

TEST(AgentRuntime, SpreadRecordsFallOnATickSetByTheIdNeverTheFirst) {
  // Ids 1..5 take the five ticks of every five; the first tick, sent before the law linked
  // anyone, is never a record (id 5 records its sixth instead).
  const std::vector<std::vector<int>> want = {
      {2, 7, 12}, {3, 8, 13}, {4, 9, 14}, {5, 10, 15}, {6, 11, 16}};
  for (AgentId id = 1; id <= 5; ++id)
    for (const int announcements : {0, 1, 3, 4, 12})
      EXPECT_EQ(recorded_ticks(id, announcements, true), want[id - 1])
          << "agent " << id << " after " << announcements << " announcements";
}

}  // namespace
}  // namespace qswarm
