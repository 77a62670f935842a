// The product's agent loop (barrier, pacing, join, kill, restart, faults) in one process, on a
// manual clock over the in-memory network: deterministic, and seconds of swarm in milliseconds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include "common/core/law_registry.hpp"
#include "common/runtime/neighbourhood.hpp"
#include "common/scenario/scenario.hpp"
#include "common/sim/in_process_swarm.hpp"
#include "common/transport/in_memory_bus.hpp"
#include "tests/sim/recorded_run.hpp"
#include "tests/sim/six_agents.hpp"

namespace qswarm {
namespace {

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

TEST(InProcessSwarm, AnAgentThatNeverComesHoldsTheWholeSwarmUntilTheStartTimeout) {
  // Given twelve agents in a line 3 m apart over 3.5 m radio links, each hearing only the agents
  // near it, and agent 12 dead before it announced anything
  std::string text =
      "name: \"line\" mode: PARTICLE law: EDGE_FLOW weight { policy: UNWEIGHTED }\n"
      "topology { policy: RANGE threshold_m: 3.5 } duration_s: 120 seed: 1\n"
      "transport { delivery: NEIGHBOURS }\n";
  for (int id = 1; id <= 12; ++id)
    text += "agents { id: " + std::to_string(id) + " position { x: " + std::to_string(3 * id) +
            " y: 0 z: 0 } }\n";
  const RunConfig rc = resolve_scenario(parse_scenario_text(text, "line"));
  ASSERT_EQ(start_peers(rc, 1).count(12), 0u);  // agent 1 does not hear it
  InProcessSwarm swarm(rc);
  swarm.crash(12);
  // When the others wait for it
  ASSERT_TRUE(swarm.run_until(
      [&] {
        for (AgentId id = 1; id <= 11; ++id)
          if (swarm.agent(id)->phase() != LifePhase::kRunning) return false;
        return true;
      },
      rc.plan.start_timeout_s + 5.0));
  // Then nobody ran before the start timeout, not even the far end of the line, and then all
  // started together (each at its first poll past the timeout: a beacon period at most, 75 ms
  // for agent 11, which never heard all its peers), each saying why
  for (AgentId id = 1; id <= 11; ++id) {
    EXPECT_GE(swarm.agent(id)->running_since_s(), rc.plan.start_timeout_s) << id;
    EXPECT_LT(swarm.agent(id)->running_since_s(), rc.plan.start_timeout_s + 0.1) << id;
  }
  // (the first to time out say so; the others may follow a running neighbour)
  EXPECT_GE(std::count_if(
                swarm.log().begin(), swarm.log().end(),
                [](const std::string& l) { return l.find("start timeout") != std::string::npos; }),
            1);
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

// Six agents fly while a stranger on their network publishes, where agent 2 does, what `forge`
// makes of each sequence number; they must agree on their exact average and every agent that
// hears agent 2 must have dropped the stranger's samples.
void fly_beside_a_stranger(const std::function<StateMessage(std::uint64_t seq)>& forge) {
  InProcessSwarm swarm(six());
  InMemoryBus stranger(swarm.network());
  stranger.set_interest({swarm.agent(2)->interest().publish, {}, {}});
  std::uint64_t seq = 1u << 30;
  ASSERT_TRUE(swarm.run_until(
      [&] {
        stranger.publish(forge(++seq));
        return swarm.wall_s() > 1.0 && swarm.disagreement_running() < 1e-8;
      },
      20.0));
  EXPECT_LT(relative_error_of_mean(swarm), 1e-12);
  for (AgentId id = 1; id <= 6; ++id) {
    if (id == 2) continue;  // agent 2 does not listen where it publishes itself
    EXPECT_GT(swarm.agent(id)->transport_counters().dropped, 10u) << "agent " << id;
  }
}

TEST(InProcessSwarm, AStrangerSendingNanAndImpersonationsIsDroppedAndChangesNothing) {
  fly_beside_a_stranger([](std::uint64_t seq) {
    StateMessage bad;
    bad.view.id = 2;  // impersonates agent 2 with NaN
    bad.view.q = Vec3(std::nan(""), 0, 0);
    bad.phase = Phase::kRunning;
    bad.seq = seq;
    bad.incarnation = 99;
    return bad;
  });
}

TEST(InProcessSwarm, AnotherLawsSamplesNeverReachTheLawInProcessEither) {
  // The in-process swarm's gates expect the run's law, as the DDS bus's do: a well-formed sample
  // of agent 2 from another law, with a far-off state, is dropped and moves nothing.
  fly_beside_a_stranger([](std::uint64_t seq) {
    StateMessage other;
    other.view.id = 2;
    other.view.q = Vec3(500, 500, 500);
    other.view.law = law_tag("laplacian");
    other.phase = Phase::kRunning;
    other.seq = seq;
    other.incarnation = 99;
    return other;
  });
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

std::vector<std::string> event_kinds(const RunDir& dir) {
  std::vector<std::string> kinds;
  for (const auto& [kind, detail] : events_of(dir)) kinds.push_back(kind);
  return kinds;
}

TEST(RecordedRun, TheSupervisorsOwnRecorderJudgesAnInProcessRunConverged) {
  // Given six agents and the supervisor's loop on one manual clock
  const RunDir dir = fresh_run_dir();
  InProcessSwarm swarm(six(), 1.0, dir);
  // When the run goes until the supervisor ends it
  EXPECT_EQ(swarm.run_recorded(60.0), "converged");
  // Then the verdict, the exit code and the record are the real ones
  EXPECT_EQ(swarm.supervisor()->exit_code(), 0);
  const records::Summary s = summary_of(dir);
  EXPECT_TRUE(s.converged());
  EXPECT_EQ(s.end_reason(), "converged");
  EXPECT_EQ(s.agents_size(), 6);
  EXPECT_EQ(s.joins(), 6u);
  EXPECT_LT(s.average_relative_error(), 1e-9);  // edge-flow: the exact average
  EXPECT_LT(s.final_disagreement_m(), 1e-8);
  EXPECT_GT(s.convergence_time_s(), 0.0);
  const std::vector<std::string> kinds = event_kinds(dir);
  EXPECT_EQ(std::count(kinds.begin(), kinds.end(), "join"), 6);
  EXPECT_EQ(std::count(kinds.begin(), kinds.end(), "converged"), 1);
  EXPECT_EQ(kinds.back(), "end");
  EXPECT_TRUE(std::filesystem::exists(dir.records()));
  // The recorder heard every 5th sample of each agent (10 Hz of a 50 Hz swarm) and their goodbyes,
  // no sequence number lost.
  std::ifstream telemetry(dir.telemetry());
  std::string row;
  std::getline(telemetry, row);  // header
  int rows = 0;
  while (std::getline(telemetry, row)) {
    std::stringstream fields(row);
    std::string stamp, id, seq, phase;
    std::getline(fields, stamp, ',');
    std::getline(fields, id, ',');
    std::getline(fields, seq, ',');
    std::getline(fields, phase, ',');
    if (phase != "2") {
      EXPECT_EQ(std::stoull(seq) % 5, 0u) << row;
    }
    ++rows;
  }
  EXPECT_GT(rows, 6 * 10);
  EXPECT_EQ(s.messages().seq_gaps(), 0u);
}

// A neighbour's sample carries no links unless a place filter reads them (REACH); the recorder's
// carry the links and the initial graph, so graph.csv is whole either way.
TEST(RecordedRun, LinksRideToTheRecorderAndToNeighboursOnlyWhereAFilterReadsThem) {
  for (const char* delivery : {"ALL", "NEIGHBOURS", "REACH"}) {
    SCOPED_TRACE(delivery);
    const RunDir dir = fresh_run_dir(delivery);
    InProcessSwarm swarm(six(std::string("transport { delivery: ") + delivery + " }"), 1.0, dir);
    std::size_t samples = 0, samples_with_links = 0, samples_with_initial = 0;
    std::size_t records = 0, records_with_links = 0, records_with_initial = 0;
    swarm.network().set_rewrite([&](const InMemoryBus&, const InMemoryBus& to, StateMessage& m) {
      if (m.phase != Phase::kRunning) return;
      const bool recorder = to.role() == InMemoryBus::Role::kRecorder;
      ++(recorder ? records : samples);
      if (!m.links.empty()) ++(recorder ? records_with_links : samples_with_links);
      if (!m.initial_links.empty()) ++(recorder ? records_with_initial : samples_with_initial);
    });
    EXPECT_EQ(swarm.run_recorded(60.0), "converged");
    ASSERT_GT(samples, 1000u);
    ASSERT_GT(records, 100u);
    EXPECT_EQ(records_with_links, records);
    EXPECT_EQ(records_with_initial, records);
    EXPECT_EQ(samples_with_initial, 0u);
    if (std::string(delivery) == "REACH") {
      // All but the first running samples, sent before the law's first tick linked anyone.
      EXPECT_GT(samples_with_links, samples * 99 / 100);
    } else {
      EXPECT_EQ(samples_with_links, 0u);
    }
    // The record's initial graph (from the initial links) is the complete one.
    EXPECT_EQ(summary_of(dir).edges_initial_size(), 15);
  }
}

TEST(RecordedRun, AnAgentThatCrashedIsMissingSoTheRunDoesNotConverge) {
  // Given six agents, one of which crashes once everyone runs (no plan expects it gone)
  const RunDir dir = fresh_run_dir();
  InProcessSwarm swarm(six(), 1.0, dir);
  ASSERT_TRUE(swarm.run_until([&] { return all_running(swarm) && swarm.wall_s() > 0.5; }, 5.0));
  swarm.crash(4);
  // When the others agree without it
  const std::string reason = swarm.run_recorded(60.0);
  // Then the run says so and is not converged
  EXPECT_EQ(reason, "agreed without agent 4");
  EXPECT_EQ(swarm.supervisor()->exit_code(), 1);
  const records::Summary s = summary_of(dir);
  EXPECT_FALSE(s.converged());
  ASSERT_EQ(s.missing_agents_size(), 1);
  EXPECT_EQ(s.missing_agents(0), 4u);
  EXPECT_EQ(s.departures(), 1u);
  const std::vector<std::string> kinds = event_kinds(dir);
  EXPECT_EQ(std::count(kinds.begin(), kinds.end(), "agreed_without"), 1);
  EXPECT_EQ(std::count(kinds.begin(), kinds.end(), "converged"), 0);
}

TEST(RecordedRun, AKillAndRestartUnderTheRestartPolicyEndsConvergedAtTheExactAverage) {
  // Given agent 3 killed at 1.5 s and restarted at 3 s by the plan
  const RunDir dir = fresh_run_dir();
  InProcessSwarm swarm(six("faults { kill { agent: 3 at_s: 1.5 restart_at_s: 3 } }"), 1.0, dir);
  // When the run goes until the supervisor ends it
  EXPECT_EQ(swarm.run_recorded(60.0), "converged");
  // Then the policy respawned it once, it recovered its flows, and the record counts both
  int respawns = 0;
  for (const std::string& line : swarm.log())
    respawns += line.find(" 3 respawned") != std::string::npos;
  EXPECT_EQ(respawns, 1);
  EXPECT_EQ(swarm.agent(3)->runtime().recovered_flows(), 3);
  const records::Summary s = summary_of(dir);
  EXPECT_TRUE(s.converged());
  EXPECT_EQ(s.faults().kills(), 1u);
  EXPECT_EQ(s.faults().restarts(), 1u);
  // The kill (1.5 s) was seen as a departure, after it and before the restart (3 s).
  EXPECT_GT(s.detect_s(), 0.0);
  EXPECT_LT(s.detect_s(), 1.5);
  EXPECT_LT(s.average_relative_error(), 1e-9);
  const std::vector<std::string> kinds = event_kinds(dir);
  EXPECT_EQ(std::count(kinds.begin(), kinds.end(), "depart"), 1);
  EXPECT_EQ(std::count(kinds.begin(), kinds.end(), "rejoin"), 1);
}

TEST(RestartPolicy, OnlyAMarkedPlannedKillRestartsAndOnlyAsOftenAsThePlanSays) {
  const RunConfig rc =
      six("faults { kill { agent: 3 at_s: 1 restart_at_s: 2 } kill { agent: 3 at_s: 4 } }");
  RestartPolicy policy(rc.faults);
  EXPECT_FALSE(policy.is_planned_kill(3, 0));  // nothing marked: a SIGKILL from outside
  EXPECT_FALSE(policy.is_planned_kill(5, 1));  // no kill planned for agent 5
  ASSERT_TRUE(policy.is_planned_kill(3, 1));
  EXPECT_EQ(policy.after_planned_kill(3), std::optional<double>(2.0));
  EXPECT_FALSE(policy.is_planned_kill(3, 1));  // that mark is used up
  ASSERT_TRUE(policy.is_planned_kill(3, 2));
  EXPECT_EQ(policy.after_planned_kill(3), std::nullopt);  // the second kill is final
  EXPECT_FALSE(policy.is_planned_kill(3, 3));             // the plan has no third
  EXPECT_EQ(policy.restarts(3), 1);
}

}  // namespace
}  // namespace qswarm
