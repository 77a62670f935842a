// An insider that lies, in the in-process swarm: the real agent runtime of every agent over the
// in-memory network, agent 7 telling everyone (or each its own) a false consensus state, and the
// supervisor's own recorder judging the run. The recorder cannot tell a liar from an honest agent
// that is stuck: what it can say honestly is who stayed away while the others agreed.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

#include "common/scenario/scenario.hpp"
#include "common/sim/in_process_swarm.hpp"
#include "tests/sim/recorded_run.hpp"

namespace qswarm {
namespace {

// scenarios/insider_seven.txtpb: seven point agents on the complete graph, W-MSR with F = 1.
RunConfig insider_seven(const std::string& law = "") {
  ScenarioOverrides o;
  o.law = law;
  return load_scenario(std::string(QSWARM_SOURCE_DIR) + "/scenarios/insider_seven.txtpb", o);
}

int count_kind(const std::vector<std::pair<std::string, std::string>>& ev, const std::string& k) {
  return static_cast<int>(
      std::count_if(ev.begin(), ev.end(), [&](const auto& e) { return e.first == k; }));
}

std::vector<Liar> attacks() {
  return {{7, Liar::Kind::kConstant, kDefaultLie},
          {7, Liar::Kind::kDrift, kDefaultDrift_mps},
          {7, Liar::Kind::kSplit, kDefaultLie}};
}

// The honest agents' consensus states now, and where they started.
struct Honest {
  Positions q, q0;
};
Honest honest(const InProcessSwarm& s, AgentId liar) {
  Honest h;
  for (const AgentSpec& a : s.config().agents) {
    if (a.id == liar) continue;
    h.q.push_back(s.agent(a.id)->runtime().consensus());
    h.q0.push_back(a.q0());
  }
  return h;
}

TEST(Insider, WmsrKeepsTheHonestAgentsInTheirBoxAndTheRecordNamesWhoStayedAway) {
  for (const Liar& liar : attacks()) {
    SCOPED_TRACE(to_string(liar.kind));
    // Given seven agents running W-MSR (F = 1), agent 7 lying to everyone from the start
    const RunDir dir = fresh_run_dir(to_string(liar.kind));
    InProcessSwarm swarm(insider_seven(), 1.0, dir);
    swarm.add_liar(liar);
    // When the supervisor's recorder judges the run
    const std::string reason = swarm.run_recorded(130.0);
    // Then the six honest agents agreed inside their initial bounding box
    const Honest h = honest(swarm, 7);
    EXPECT_LT(disagreement(h.q), 1e-6);
    EXPECT_LT(outside_box_m(h.q, h.q0), 1e-9);
    // and the record says the others agreed without agent 7, which is no convergence
    EXPECT_EQ(reason, "agreed except agent 7 (a liar w-msr ignored, or an agent cut off)");
    EXPECT_EQ(swarm.supervisor()->exit_code(), 1);
    const records::Summary s = summary_of(dir);
    EXPECT_FALSE(s.converged());
    ASSERT_EQ(s.outlier_agents_size(), 1);
    EXPECT_EQ(s.outlier_agents(0), 7u);
    EXPECT_FALSE(s.has_agreed_elsewhere_m());
    EXPECT_EQ(s.missing_agents_size(), 0);
    const auto ev = events_of(dir);
    EXPECT_EQ(count_kind(ev, "agreed_except"), 1);
    EXPECT_EQ(count_kind(ev, "converged"), 0);
    // The complete graph held W-MSR's condition throughout, and the honest laws trimmed values.
    ASSERT_TRUE(s.has_resilience());
    EXPECT_EQ(s.resilience().f(), 1u);
    EXPECT_EQ(s.resilience().min_degree(), 6u);
    EXPECT_EQ(s.resilience().degree_short_s(), 0.0);
    EXPECT_TRUE(s.resilience().robust_always());
    EXPECT_EQ(s.resilience().robustness_checks(), 1u);  // one graph, checked once
    EXPECT_EQ(count_kind(ev, "resilience_lost"), 0);
    EXPECT_GT(s.resilience().trimmed(), 0u);
    for (const records::AgentSummary& a : s.agents()) EXPECT_GT(a.trimmed(), 0u) << a.id();
  }
}

TEST(Insider, EdgeFlowFollowsTheLiarAndItsRunNeverEndsConverged) {
  for (const Liar& liar : attacks()) {
    SCOPED_TRACE(to_string(liar.kind));
    // Given the same seven agents and liar, under edge-flow
    const RunDir dir = fresh_run_dir(to_string(liar.kind));
    InProcessSwarm swarm(insider_seven("edge-flow"), 1.0, dir);
    swarm.add_liar(liar);
    const std::string reason = swarm.run_recorded(130.0);
    // Then the honest agents left their initial box, following the liar
    const Honest h = honest(swarm, 7);
    EXPECT_GT(outside_box_m(h.q, h.q0), 10.0);
    // and the run did not converge: under the constant lie everyone "agreed" on the liar's
    // point, which edge-flow's record knows is not the initial average
    EXPECT_EQ(swarm.supervisor()->exit_code(), 1);
    const records::Summary s = summary_of(dir);
    EXPECT_FALSE(s.converged());
    EXPECT_EQ(s.outlier_agents_size(), 0);  // not a W-MSR run: nobody is set aside
    EXPECT_FALSE(s.has_resilience());
    if (liar.kind == Liar::Kind::kConstant) {
      EXPECT_NE(reason.find("from the initial average"), std::string::npos) << reason;
      EXPECT_GT(s.agreed_elsewhere_m(), 1000.0);
    } else {
      EXPECT_EQ(reason, "duration");  // drift: always behind it; split: two camps
    }
  }
}

TEST(Insider, TwoLiarsAgainstFEqualOneDragTheOthersAndTheRecordSaysTheBoxWasLeft) {
  // Given W-MSR tolerating F = 1, and two agents telling everyone the same far point
  const RunDir dir = fresh_run_dir("two");
  InProcessSwarm swarm(insider_seven(), 1.0, dir);
  swarm.add_liar({6, Liar::Kind::kConstant, kDefaultLie});
  swarm.add_liar({7, Liar::Kind::kConstant, kDefaultLie});
  // When the run is judged
  const std::string reason = swarm.run_recorded(130.0);
  // Then one trimmed value is not enough: the honest five are dragged to the liars' point
  Positions q, q0;
  for (const AgentSpec& a : swarm.config().agents) {
    if (a.id >= 6) continue;
    q.push_back(swarm.agent(a.id)->runtime().consensus());
    q0.push_back(a.q0());
  }
  EXPECT_GT(outside_box_m(q, q0), 1000.0);
  // and everyone "agreed", but outside where W-MSR keeps agents that do not lie: not converged
  EXPECT_NE(reason.find("outside the agents' initial bounding box, which w-msr keeps: more than "
                        "F = 1 liars, or too few links?"),
            std::string::npos)
      << reason;
  EXPECT_EQ(swarm.supervisor()->exit_code(), 1);
  const records::Summary s = summary_of(dir);
  EXPECT_FALSE(s.converged());
  EXPECT_GT(s.agreed_elsewhere_m(), 1000.0);
  EXPECT_EQ(s.outlier_agents_size(), 0);
}

// Four agents on K4, W-MSR with F = 1: every agent reads 3 = 2F+1 neighbours, and K4 is
// (2, 2)-robust.
const char* kFour = R"(
name: "four"
agents { id: 1 position { x: 0 y: 0 z: 0 } }
agents { id: 2 position { x: 10 y: 0 z: 0 } }
agents { id: 3 position { x: 0 y: 10 z: 0 } }
agents { id: 4 position { x: 0 y: 0 z: 10 } }
mode: PARTICLE
law: W_MSR
wmsr_f: 1
weight { policy: UNWEIGHTED }
topology { policy: PROXIMITY threshold_m: 1000 }
convergence { tolerance_m: 1e-6 hold_s: 1 }
duration_s: 30
)";

TEST(ResilienceOverTime, ACrashThatLeavesTooFewNeighboursIsInTheRecordWhenItHappens) {
  // Given four agents on K4 under W-MSR (F = 1), one of which crashes once all run
  const RunDir dir = fresh_run_dir("four");
  InProcessSwarm swarm(resolve_scenario(parse_scenario_text(kFour, "four")), 1.0, dir);
  ASSERT_TRUE(swarm.run_until([&] { return swarm.running_states().size() == 4; }, 5.0));
  ASSERT_TRUE(swarm.run_until([&] { return swarm.wall_s() > 1.0; }, 5.0));
  swarm.crash(4);
  // When the run ends
  const std::string reason = swarm.run_recorded(60.0);
  EXPECT_EQ(reason, "agreed without agent 4");
  // Then the record says when the three left read only 2 neighbours, fewer than 2F+1 = 3
  const records::Summary s = summary_of(dir);
  ASSERT_TRUE(s.has_resilience());
  EXPECT_EQ(s.resilience().min_degree(), 2u);
  EXPECT_GT(s.resilience().first_degree_short_s(), 1.0);
  EXPECT_GT(s.resilience().degree_short_s(), 0.0);
  // K3 is still (2, 2)-robust; K4 and K3 were each checked once.
  EXPECT_TRUE(s.resilience().robust_always());
  EXPECT_EQ(s.resilience().robustness_checks(), 2u);
  const auto ev = events_of(dir);
  ASSERT_EQ(count_kind(ev, "resilience_lost"), 1);
  for (const auto& [kind, detail] : ev) {
    if (kind != "resilience_lost") continue;
    EXPECT_NE(detail.find("an agent reads 2 neighbours; w-msr with F = 1 needs 3"),
              std::string::npos)
        << detail;
  }
  // and graph.csv has the degree and robustness of every snapshot
  std::ifstream graph(dir.graph());
  std::string header;
  std::getline(graph, header);
  EXPECT_NE(header.find("min_degree,robust,trimmed_disagreement_m"), std::string::npos);
}

TEST(ResilienceOverTime, AGraphWithEnoughDegreeButNoRobustnessIsRecordedAsNotRobust) {
  // Two K4 joined by one edge (FIXED): degree 3 everywhere, not (2, 2)-robust.
  std::string text = R"(
name: "bridged"
mode: PARTICLE
law: W_MSR
wmsr_f: 1
weight { policy: UNWEIGHTED }
convergence { tolerance_m: 1e-6 hold_s: 1 }
duration_s: 5
topology { policy: FIXED
)";
  for (int base : {1, 5})
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j)
        text +=
            "  edges { a: " + std::to_string(base + i) + " b: " + std::to_string(base + j) + " }\n";
  text += "  edges { a: 4 b: 5 }\n}\n";
  for (int id = 1; id <= 8; ++id)
    text += "agents { id: " + std::to_string(id) + " position { x: " + std::to_string(3 * id) +
            " y: " + std::to_string(id % 3) + " z: 1 } }\n";
  const RunDir dir = fresh_run_dir("bridged");
  InProcessSwarm swarm(resolve_scenario(parse_scenario_text(text, "bridged")), 1.0, dir);
  swarm.run_recorded(30.0);
  const records::Summary s = summary_of(dir);
  ASSERT_TRUE(s.has_resilience());
  EXPECT_EQ(s.resilience().min_degree(), 3u);
  EXPECT_EQ(s.resilience().degree_short_s(), 0.0);
  EXPECT_FALSE(s.resilience().robust_always());
  EXPECT_GT(s.resilience().not_robust_s(), 3.0);
  const auto ev = events_of(dir);
  EXPECT_EQ(count_kind(ev, "resilience_lost"), 1);
  EXPECT_EQ(count_kind(ev, "resilience_restored"), 0);
}

}  // namespace
}  // namespace qswarm
