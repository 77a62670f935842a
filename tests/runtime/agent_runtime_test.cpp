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

}  // namespace
}  // namespace qswarm
