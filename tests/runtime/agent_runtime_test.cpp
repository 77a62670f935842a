// The agent's runtime as its process drives it: what a sample carries when it is handed over.
#include <gtest/gtest.h>

#include <vector>

#include "common/clock/clock.hpp"
#include "common/runtime/agent_runtime.hpp"
#include "common/scenario/scenario.hpp"
#include "common/transport/neighbor_bus.hpp"

namespace qswarm {
namespace {

// A transport that keeps, with every sample handed to it, the clock's wall time at that moment.
class StampCheckingBus final : public NeighborBus {
 public:
  explicit StampCheckingBus(const Clock& clock) : clock_(clock) {}
  struct Handed {
    std::int64_t carried, at;
  };
  std::vector<Handed> published, recorded;

  void publish(const StateMessage& m) override {
    published.push_back({m.wall_ns, clock_.wall_ns()});
  }
  void record(const StateMessage& m) override { recorded.push_back({m.wall_ns, clock_.wall_ns()}); }
  void for_each_latest(AgentId, const std::function<void(const StateMessage&)>&) override {}
  void set_listener(Listener) override {}
  BusCounters counters() const override { return {}; }

 private:
  const Clock& clock_;
};

AgentParams lone_agent() {
  const RunConfig rc =
      resolve_scenario(parse_scenario_text("agents { id: 1 position { x: 0 y: 0 z: 10 } }\n"
                                           "rates { physics_hz: 500 consensus_hz: 50 }\n",
                                           "lone"));
  return AgentParams{*rc.spec(1), rc.agent, {}};
}

TEST(AgentRuntime, ASampleCarriesTheWallTimeAtWhichItIsHandedOverNotTheTicksStart) {
  // Given an agent on a clock that moves 1 ms with each physics step (a slow tick)
  ManualClock clock;
  StampCheckingBus bus(clock);
  AgentRuntime a(lone_agent(), bus);
  a.set_wall_clock(&clock);
  // When it flies three consensus ticks of ten steps each
  for (int i = 0; i < 30; ++i) {
    (void)a.step();
    clock.advance(0.001);
  }
  // Then every sample carries the time it was handed to the transport, which differs from tick to
  // tick by the steps between them
  ASSERT_EQ(bus.published.size(), 3u);
  for (const auto& h : bus.published) EXPECT_EQ(h.carried, h.at);
  EXPECT_EQ(bus.published[1].carried - bus.published[0].carried, 10'000'000);
  ASSERT_FALSE(bus.recorded.empty());
  EXPECT_EQ(bus.recorded.front().carried, bus.published.front().carried);
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
