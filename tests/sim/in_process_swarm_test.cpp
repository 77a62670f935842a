// The product's agent loop (barrier, pacing, join, kill, restart, faults) in one process, on a
// manual clock over the in-memory network: deterministic, and seconds of swarm in milliseconds.
#include <gtest/gtest.h>

#include <cmath>

#include "common/scenario/scenario.hpp"
#include "common/sim/in_process_swarm.hpp"
#include "common/transport/in_memory_bus.hpp"

namespace qswarm {
namespace {

// Six point agents on the complete graph, unweighted (scenarios/faults_six.txtpb): agreement is
// exponential, so the average can be checked to 1e-9. Initial average (14, 9, 20).
const char* kSix = R"(
name: "six"
agents { id: 1 position { x: 4 y: 17 z: 24 } }
agents { id: 2 position { x: 18 y: 10 z: 32 } }
agents { id: 3 position { x: 15 y: 10 z: 26 } }
agents { id: 4 position { x: 4 y: 2 z: 35 } }
agents { id: 5 position { x: 30 y: 5 z: 3 } }
agents { id: 6 position { x: 13 y: 10 z: 0 } }
mode: PARTICLE
law: EDGE_FLOW
weight { policy: UNWEIGHTED }
topology { policy: PROXIMITY threshold_m: 1000 }
convergence { tolerance_m: 1e-8 hold_s: 1 }
duration_s: 60
seed: 3
)";

RunConfig six(const std::string& extra = "") {
  return resolve_scenario(parse_scenario_text(std::string(kSix) + extra, "six"));
}

bool all_running(const InProcessSwarm& s) {
  for (const AgentSpec& a : s.config().agents) {
    const AgentLoop* l = s.agent(a.id);
    if (!l || l->phase() != LifePhase::kRunning) return false;
  }
  return true;
}

double relative_error_of_mean(const InProcessSwarm& s) {
  const Vec3 avg = s.config().initial_average();
  return (average(s.running_states()) - avg).norm() / avg.norm();
}

TEST(InProcessSwarm, BarrierStartsEveryoneTogetherOnTheWholeInitialGraphAndTheyMeetAtTheAverage) {
  InProcessSwarm swarm(six());
  ASSERT_TRUE(swarm.run_until([&] { return all_running(swarm); }, 1.0));
  // Everyone entered Phase::kRunning in the same round, within a few announce periods of the start.
  const double t0 = swarm.agent(1)->running_since_s();
  EXPECT_LT(t0, 0.05);
  for (AgentId id = 2; id <= 6; ++id) EXPECT_DOUBLE_EQ(swarm.agent(id)->running_since_s(), t0);
  swarm.run_until_wall(t0 + 0.1);
  for (AgentId id = 1; id <= 6; ++id) {
    const AgentRuntime& a = swarm.agent(id)->runtime();
    EXPECT_EQ(a.law().links().size(), 5u) << "agent " << id;  // complete graph at the first tick
    EXPECT_LE(a.law_start_s(), 0.021) << "agent " << id;
  }
  ASSERT_TRUE(swarm.run_until([&] { return swarm.disagreement_running() < 1e-8; }, 20.0));
  EXPECT_LT(relative_error_of_mean(swarm), 1e-12);
}

TEST(InProcessSwarm, ALateJoinerDoesNotStallTheOthersAndBringsItsStartIntoTheAverage) {
  InProcessSwarm swarm(six("faults { late_join { agent: 6 at_s: 2 } }"));
  swarm.run_until_wall(0.5);
  EXPECT_EQ(swarm.agent(6)->phase(), LifePhase::kJoinWait);
  for (AgentId id = 1; id <= 5; ++id) {
    // The others' law starts at its first tick: no 1 s grace waiting for the late joiner.
    const double started = swarm.agent(id)->runtime().law_start_s();
    EXPECT_GE(started, 0.0) << "agent " << id;
    EXPECT_LE(started, 0.021) << "agent " << id;
  }
  ASSERT_TRUE(swarm.run_until([&] { return all_running(swarm); }, 3.0));
  EXPECT_GE(swarm.agent(6)->runtime().time_s(), 2.0);
  ASSERT_TRUE(swarm.run_until(
      [&] { return swarm.wall_s() > 3.0 && swarm.disagreement_running() < 1e-8; }, 30.0));
  EXPECT_LT(relative_error_of_mean(swarm), 1e-9);
}

TEST(InProcessSwarm, AKilledAndRestartedAgentRecoversItsFlowsAndTheAverageStaysExact) {
  InProcessSwarm swarm(six("faults { kill { agent: 3 at_s: 1.5 restart_at_s: 3 } }"));
  swarm.run_until_wall(2.0);
  EXPECT_EQ(swarm.agent(3)->phase(), LifePhase::kJoinWait);  // the respawn waits for 3 s
  bool killed = false;
  for (const std::string& line : swarm.log())
    killed |= line.find(" 3 planned kill") != std::string::npos;
  EXPECT_TRUE(killed);
  ASSERT_TRUE(swarm.run_until([&] { return all_running(swarm); }, 4.0));
  ASSERT_TRUE(swarm.run_until(
      [&] { return swarm.wall_s() > 4.0 && swarm.disagreement_running() < 1e-8; }, 30.0));
  EXPECT_EQ(swarm.agent(3)->runtime().recovered_flows(), 3);  // it owns 3-4, 3-5, 3-6
  EXPECT_LT(relative_error_of_mean(swarm), 1e-9);
}

TEST(InProcessSwarm, APartitionAgreesPerSideThenGloballyAfterHealing) {
  InProcessSwarm swarm(six("faults { partition { group: [1, 2, 3] start_s: 0 end_s: 8 } }"));
  swarm.run_until_wall(7.5);
  // Just before the heal, each side sits at its own initial average: edge-flow moved nothing
  // across links that never carried a message.
  const Vec3 side_a = (Vec3(4, 17, 24) + Vec3(18, 10, 32) + Vec3(15, 10, 26)) / 3.0;
  const Vec3 side_b = (Vec3(4, 2, 35) + Vec3(30, 5, 3) + Vec3(13, 10, 0)) / 3.0;
  for (AgentId id = 1; id <= 6; ++id) {
    const Vec3 q = swarm.agent(id)->runtime().consensus();
    EXPECT_LT((q - (id <= 3 ? side_a : side_b)).norm(), 1e-6) << "agent " << id;
  }
  EXPECT_GT(swarm.agent(1)->fault_counters().partition, 0u);
  ASSERT_TRUE(swarm.run_until(
      [&] { return swarm.wall_s() > 8.0 && swarm.disagreement_running() < 1e-8; }, 40.0));
  EXPECT_LT(relative_error_of_mean(swarm), 1e-9);
}

TEST(InProcessSwarm, AStrangerSendingNanAndImpersonationsIsDroppedAndChangesNothing) {
  InProcessSwarm swarm(six());
  InMemoryBus stranger(swarm.network());
  std::uint64_t seq = 1u << 30;
  ASSERT_TRUE(swarm.run_until(
      [&] {
        StateMessage bad;
        bad.view.id = 2;  // impersonates agent 2 with NaN
        bad.view.q = Vec3(std::nan(""), 0, 0);
        bad.phase = Phase::kRunning;
        bad.seq = ++seq;
        bad.incarnation = 99;
        stranger.publish(bad);
        return swarm.wall_s() > 1.0 && swarm.disagreement_running() < 1e-8;
      },
      20.0));
  EXPECT_LT(relative_error_of_mean(swarm), 1e-12);
  for (AgentId id = 1; id <= 6; ++id)
    EXPECT_GT(swarm.agent(id)->transport_counters().dropped, 10u) << "agent " << id;
}

TEST(InProcessSwarm, ARunReplaysExactly) {
  const auto final_states = [] {
    InProcessSwarm swarm(six("faults { loss { probability: 0.3 } }"));
    swarm.run_until_wall(3.0);
    return swarm.running_states();
  };
  const Positions a = final_states(), b = final_states();
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i], b[i]);
}

}  // namespace
}  // namespace qswarm
