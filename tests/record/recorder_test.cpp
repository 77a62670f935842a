// The recorder's parts, fed with messages and told the time.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <sstream>
#include <string>

#include "common/record/convergence.hpp"
#include "common/record/graph_metrics.hpp"
#include "common/record/presence.hpp"
#include "common/record/recorder.hpp"
#include "common/record/separation.hpp"
#include "common/scenario/scenario.hpp"
#include "tests/core/paper_data.hpp"

namespace qswarm {
namespace {

StateMessage sample(AgentId id, std::uint64_t seq, double t, const Vec3& q,
                    Phase phase = Phase::kRunning) {
  StateMessage m;
  m.view.id = id;
  m.view.q = q;
  m.view.q0 = q;
  m.view.seq = seq;
  m.p_W = q;
  m.seq = seq;
  m.stamp_s = t;
  m.phase = phase;
  m.incarnation = 1;
  return m;
}

// An empty directory of this name (and process) under the system's temporary one.
std::filesystem::path fresh_dir(const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / (name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

TEST(Presence, JoinsDepartsInSwarmTimeAndRejoins) {
  Presence p({1, 2}, 1.0);
  EXPECT_EQ(p.on_sample(sample(1, 1, 0.0, Vec3::Zero()), 0.0), Presence::Change::kJoin);
  EXPECT_EQ(p.on_sample(sample(1, 2, 0.02, Vec3::Zero()), 0.02), Presence::Change::kNone);
  EXPECT_EQ(p.on_sample(sample(1, 5, 0.08, Vec3::Zero()), 0.08), Presence::Change::kNone);
  EXPECT_EQ(p.track(1).gaps, 2u);  // seq 3 and 4 never arrived
  EXPECT_TRUE(p.expire(1.0).empty());
  EXPECT_EQ(p.expire(1.2), std::vector<AgentId>{1});  // silent for more than 1 s of swarm time
  EXPECT_FALSE(p.running(1));
  EXPECT_EQ(p.on_sample(sample(1, 6, 1.3, Vec3::Zero()), 1.3), Presence::Change::kRejoin);
  EXPECT_EQ(p.on_sample(sample(1, 7, 1.32, Vec3::Zero(), Phase::kStopping), 1.32),
            Presence::Change::kDepart);
  EXPECT_EQ(p.on_sample(sample(9, 1, 0.0, Vec3::Zero()), 1.4), Presence::Change::kStranger);
  EXPECT_EQ(p.on_sample(sample(9, 2, 0.0, Vec3::Zero()), 1.5), Presence::Change::kStrangerAgain);
  EXPECT_EQ(p.seen_count(), 1u);
  EXPECT_EQ(p.strangers(), 1u);
}

TEST(Presence, WithARecordRateOnlyMissingMultiplesOfItAreGaps) {
  // Agents send every 5th sample to the recorder (and their goodbye).
  Presence p({1}, 1.0, 5);
  p.on_sample(sample(1, 5, 0.1, Vec3::Zero()), 0.1);
  p.on_sample(sample(1, 10, 0.2, Vec3::Zero()), 0.2);
  EXPECT_EQ(p.track(1).gaps, 0u);  // 6..9 were never sent to it
  p.on_sample(sample(1, 25, 0.5, Vec3::Zero()), 0.5);
  EXPECT_EQ(p.track(1).gaps, 2u);  // 15 and 20 were
  p.on_sample(sample(1, 27, 0.54, Vec3::Zero(), Phase::kStopping), 0.54);
  EXPECT_EQ(p.track(1).gaps, 2u);  // a goodbye off the multiples is no gap either
}

TEST(Presence, TheTicksAnAgentSkipsAtItsFirstTickAreNoGap) {
  // Which ticks an agent records is set at its first tick: after barrier announcements up to 12,
  // its first tick can be 16 or 17 (first record 20), so 15 was never sent.
  Presence p({1}, 1.0, 5);
  p.on_sample(sample(1, 10, 0.0, Vec3::Zero(), Phase::kReady), 0.0);
  p.on_sample(sample(1, 20, 0.1, Vec3::Zero()), 0.1);
  EXPECT_EQ(p.track(1).gaps, 0u);
  p.on_sample(sample(1, 30, 0.3, Vec3::Zero()), 0.3);
  EXPECT_EQ(p.track(1).gaps, 1u);  // 25 was sent in flight
  p.on_sample(sample(1, 40, 0.5, Vec3::Zero(), Phase::kStopping), 0.5);
  EXPECT_EQ(p.track(1).gaps, 2u);  // and 35 before the goodbye
}

TEST(GraphMetrics, ThePapersWeightedNetworkHasItsSpectrum) {
  // Paper 2.7.1: graph 1 with initial-distance weights, lambda2 = 13.060.
  const std::vector<AgentId> ids = {1, 2, 3, 4};
  std::vector<std::vector<std::pair<AgentId, double>>> links(4);
  for (const auto& [a, b] : paper::kGraph1) {
    const double w = (paper::kWeightedQ0[a - 1] - paper::kWeightedQ0[b - 1]).norm();
    links[a - 1].emplace_back(b, w);
  }
  const records::GraphSnapshot g = measure_graph(
      0.0, ids, paper::kWeightedQ0,
      paper::kWeightedQ0, [&](int i) -> const auto& { return links[static_cast<size_t>(i)]; },
      paper::kWeightedAgreement);
  EXPECT_EQ(g.edges_size(), 4);
  EXPECT_NEAR(g.lambda2(), 13.060, 5e-4);
  EXPECT_EQ(g.components(), 1u);
  EXPECT_NEAR(g.mean_drift_m(), 0.0, 1e-12);  // the initial states' mean is the agreement point
  EXPECT_NEAR(g.min_separation_m(), std::sqrt(77.0), 1e-12);  // agents 2 and 4
}

TEST(GraphMetrics, AGraphThatHasNotChangedIsNotDecomposedAgainButAChangedOneIs) {
  const std::vector<AgentId> ids{1, 2, 3, 4};
  std::vector<std::vector<std::pair<AgentId, double>>> links(4);
  for (const auto& [a, b] : paper::kGraph1) links[a - 1].emplace_back(b, 1.0);
  const auto links_of = [&](int i) -> const auto& { return links[static_cast<size_t>(i)]; };
  const Positions q = paper::kWeightedQ0;
  SpectrumMemo memo;
  const double fresh = measure_graph(0.0, ids, q, q, links_of, Vec3::Zero()).lambda2();
  for (int k = 0; k < 3; ++k)
    EXPECT_EQ(
        measure_graph(0.1 * k, ids, q, q, links_of, Vec3::Zero(), {}, {}, nullptr, &memo).lambda2(),
        fresh);
  EXPECT_EQ(memo.computed, 1u);
  EXPECT_EQ(memo.reused, 2u);
  // A weight that moved, an edge that went, an agent that left: each is a new graph.
  links[0][0].second = 2.0;
  const double heavier = measure_graph(0.3, ids, q, q, links_of, Vec3::Zero()).lambda2();
  EXPECT_GT(heavier, fresh);
  EXPECT_EQ(measure_graph(0.3, ids, q, q, links_of, Vec3::Zero(), {}, {}, nullptr, &memo).lambda2(),
            heavier);
  links[0].clear();
  const records::GraphSnapshot cut =
      measure_graph(0.4, ids, q, q, links_of, Vec3::Zero(), {}, {}, nullptr, &memo);
  EXPECT_EQ(cut.lambda2(), measure_graph(0.4, ids, q, q, links_of, Vec3::Zero()).lambda2());
  const std::vector<AgentId> three{1, 2, 3};
  const Positions q3(q.begin(), q.begin() + 3);
  const records::GraphSnapshot fewer =
      measure_graph(0.5, three, q3, q3, links_of, Vec3::Zero(), {}, {}, nullptr, &memo);
  EXPECT_EQ(fewer.components(),
            measure_graph(0.5, three, q3, q3, links_of, Vec3::Zero()).components());
  EXPECT_EQ(fewer.lambda2(), measure_graph(0.5, three, q3, q3, links_of, Vec3::Zero()).lambda2());
  EXPECT_EQ(memo.computed, 4u);
  EXPECT_EQ(memo.reused, 2u);
}

// The listed agents report at swarm time t, as flying agents do every record period: a hold
// counts only once every agent was heard during it.
void hear(Presence& p, std::initializer_list<AgentId> ids, double t) {
  static std::uint64_t seq = 1000;
  for (const AgentId id : ids) p.on_sample(sample(id, ++seq, t, Vec3::Zero()), t);
}

TEST(ConvergenceJudge, HoldsForHoldSecondsAndWaitsForThePlanAndDueAgents) {
  FaultPlan plan;
  plan.kill.push_back({2, 1.0, 3.0});  // agent 2 killed at 1 s, back at 3 s
  ConvergenceJudge judge(0.01, 0.5, 1.0, -1.0, plan);
  Presence p({1, 2}, 1.0);
  p.on_sample(sample(1, 1, 0.0, Vec3::Zero()), 0.0);
  p.on_sample(sample(2, 1, 0.0, Vec3::Zero()), 0.0);
  records::GraphSnapshot agree;
  agree.set_agents(2);
  agree.set_disagreement_m(0.001);
  agree.set_spread_m(0.001);
  // Before the last planned fault ends (the restart at 3 s), agreement does not count.
  EXPECT_EQ(ConvergenceJudge::Verdict::kNone, judge.update(2.0, agree, p));
  EXPECT_EQ(ConvergenceJudge::Verdict::kNone, judge.update(2.9, agree, p));
  // After it, agent 2 is due back: it must be running.
  p.expire(3.5);  // both silent: departed
  p.on_sample(sample(1, 2, 3.5, Vec3::Zero()), 3.5);
  EXPECT_EQ(ConvergenceJudge::Verdict::kNone, judge.update(3.5, agree, p));
  EXPECT_EQ(ConvergenceJudge::Verdict::kNone, judge.update(4.5, agree, p));
  p.on_sample(sample(2, 2, 4.6, Vec3::Zero()), 4.6);
  EXPECT_EQ(ConvergenceJudge::Verdict::kNone, judge.update(4.6, agree, p));  // the hold starts
  records::GraphSnapshot apart = agree;
  apart.set_disagreement_m(0.5);
  EXPECT_EQ(ConvergenceJudge::Verdict::kNone, judge.update(4.8, apart, p));  // and restarts
  EXPECT_EQ(ConvergenceJudge::Verdict::kNone, judge.update(4.9, agree, p));
  hear(p, {1, 2}, 5.4);
  EXPECT_EQ(ConvergenceJudge::Verdict::kConverged, judge.update(5.4, agree, p));
  EXPECT_TRUE(judge.converged());
  EXPECT_DOUBLE_EQ(judge.converged_at_s(), 4.9);
  EXPECT_EQ(ConvergenceJudge::Verdict::kNone, judge.update(5.5, agree, p));  // once
}

TEST(ConvergenceJudge, AgreeingAwayFromTheAverageEdgeFlowKeepsIsNoConvergence) {
  // A forger moved the mean 72 m: the agents agree, tightly, on the wrong point. Under edge-flow
  // (max drift = the tolerance) that is its own verdict; a law without the guarantee converges.
  Presence p({1, 2}, 1.0);
  for (AgentId id : {1u, 2u}) p.on_sample(sample(id, 1, 0.0, Vec3::Zero()), 0.0);
  records::GraphSnapshot moved;
  moved.set_agents(2);
  moved.set_disagreement_m(0.001);
  moved.set_spread_m(0.001);
  moved.set_mean_drift_m(72.0);
  ConvergenceJudge edge_flow(0.01, 0.5, 1.0, 0.01, FaultPlan{});
  EXPECT_EQ(ConvergenceJudge::Verdict::kNone, edge_flow.update(1.0, moved, p));
  EXPECT_EQ(ConvergenceJudge::Verdict::kAgreedElsewhere, edge_flow.update(1.5, moved, p));
  EXPECT_FALSE(edge_flow.converged());
  EXPECT_DOUBLE_EQ(edge_flow.agreed_elsewhere_m(), 72.0);
  EXPECT_EQ(ConvergenceJudge::Verdict::kNone, edge_flow.update(2.0, moved, p));  // once
  ConvergenceJudge laplacian(0.01, 0.5, 1.0, -1.0, FaultPlan{});
  laplacian.update(1.0, moved, p);
  hear(p, {1, 2}, 1.5);
  EXPECT_EQ(ConvergenceJudge::Verdict::kConverged, laplacian.update(1.5, moved, p));
  // Within the tolerance (what flows in flight leave), edge-flow converges too.
  records::GraphSnapshot close = moved;
  close.set_mean_drift_m(0.005);
  ConvergenceJudge honest(0.01, 0.5, 1.0, 0.01, FaultPlan{});
  honest.update(1.0, close, p);
  EXPECT_EQ(ConvergenceJudge::Verdict::kConverged, honest.update(1.5, close, p));
}

TEST(ConvergenceJudge, AgentsThatAgreeWithoutAnExpectedAgentHaveNotConverged) {
  ConvergenceJudge judge(0.01, 0.5, 1.0, -1.0, FaultPlan{});
  Presence p({1, 2, 3}, 1.0);
  for (AgentId id : {1u, 2u, 3u}) p.on_sample(sample(id, 1, 0.0, Vec3::Zero()), 0.0);
  p.on_sample(sample(3, 2, 0.1, Vec3::Zero(), Phase::kStopping), 0.1);  // agent 3 gone (or stopped)
  records::GraphSnapshot agree;
  agree.set_agents(2);
  agree.set_disagreement_m(0.001);
  agree.set_spread_m(0.001);
  EXPECT_EQ(ConvergenceJudge::Verdict::kNone, judge.update(1.0, agree, p));
  EXPECT_EQ(ConvergenceJudge::Verdict::kNone, judge.update(2.0, agree, p));  // hold + timeout
  EXPECT_EQ(ConvergenceJudge::Verdict::kAgreedWithoutSome, judge.update(2.6, agree, p));
  EXPECT_FALSE(judge.converged());
  EXPECT_EQ(judge.missing(), std::vector<AgentId>{3});
  // An agent the plan kills without restart is not missing.
  FaultPlan plan;
  plan.kill.push_back({3, 0.05, 0.0});
  ConvergenceJudge planned(0.01, 0.5, 1.0, -1.0, plan);
  EXPECT_EQ(ConvergenceJudge::Verdict::kNone, planned.update(1.0, agree, p));
  hear(p, {1, 2}, 1.5);
  EXPECT_EQ(ConvergenceJudge::Verdict::kConverged, planned.update(1.5, agree, p));
}

TEST(ConvergenceJudge, EstimatesThatAgreeWhileTheBodiesAreStillApartHaveNotConverged) {
  // The agents' consensus estimates agree to 1 mm, but the quadcopters are still 0.5 m from their
  // slots (the spread): not converged, however long that holds.
  ConvergenceJudge judge(0.01, 0.5, 1.0, -1.0, FaultPlan{});
  Presence p({1, 2}, 10.0);
  for (AgentId id : {1u, 2u}) p.on_sample(sample(id, 1, 0.0, Vec3::Zero()), 0.0);
  records::GraphSnapshot flying;
  flying.set_agents(2);
  flying.set_disagreement_m(0.001);
  flying.set_spread_m(0.5);
  for (int k = 0; k <= 30; ++k) {
    hear(p, {1, 2}, 0.1 * k);
    EXPECT_EQ(ConvergenceJudge::Verdict::kNone, judge.update(0.1 * k, flying, p)) << k;
  }
  EXPECT_FALSE(judge.converged());
  // Once the bodies are there too, the hold runs and the run converges.
  records::GraphSnapshot there = flying;
  there.set_spread_m(0.001);
  EXPECT_EQ(ConvergenceJudge::Verdict::kNone, judge.update(3.1, there, p));
  hear(p, {1, 2}, 3.6);
  EXPECT_EQ(ConvergenceJudge::Verdict::kConverged, judge.update(3.6, there, p));
}

// Agents 1 and 2 report every 0.1 s from from_s to to_s, agreeing, and the presence expires the
// silent as the recorder does; until the judge says something. Returns what it said.
ConvergenceJudge::Verdict two_agree(ConvergenceJudge& judge, Presence& p, double from_s,
                                    double to_s) {
  records::GraphSnapshot agree;
  agree.set_agents(2);
  agree.set_disagreement_m(0.001);
  agree.set_spread_m(0.001);
  ConvergenceJudge::Verdict v = ConvergenceJudge::Verdict::kNone;
  for (int k = 0; from_s + 0.1 * k <= to_s + 1e-9 && v == ConvergenceJudge::Verdict::kNone; ++k) {
    const double t = from_s + 0.1 * k;
    hear(p, {1, 2}, t);
    p.expire(t);
    v = judge.update(t, agree, p);
  }
  return v;
}

TEST(ConvergenceJudge, AnAgentThatNeverCameIsMissingNotConvergence) {
  // Agent 3 is in the scenario and never sent a sample: the two that flew agree, and the verdict
  // names 3 missing once the hold and the timeout have passed; never "converged".
  ConvergenceJudge judge(0.01, 0.5, 1.0, -1.0, FaultPlan{});
  Presence p({1, 2, 3}, 1.0);
  EXPECT_EQ(two_agree(judge, p, 0.0, 3.0), ConvergenceJudge::Verdict::kAgreedWithoutSome);
  EXPECT_FALSE(judge.converged());
  EXPECT_EQ(judge.missing(), std::vector<AgentId>{3});
}

TEST(ConvergenceJudge, AnAgentStoppedWithoutAWordIsMissingNotConvergence) {
  // Agent 3 flew, then fell silent mid-run without saying goodbye (SIGSTOP, a frozen host), just as
  // the three agreed: its last word cannot vouch for the hold, and once the presence timeout names
  // it departed, the two left agreeing is no convergence.
  ConvergenceJudge judge(0.01, 0.5, 1.0, -1.0, FaultPlan{});
  Presence p({1, 2, 3}, 1.0);
  hear(p, {1, 2, 3}, 0.0);
  records::GraphSnapshot three;
  three.set_agents(3);
  three.set_disagreement_m(0.001);
  three.set_spread_m(0.001);
  EXPECT_EQ(ConvergenceJudge::Verdict::kNone, judge.update(0.0, three, p));  // the hold starts
  // Past the hold, within the presence timeout: agent 3 is still present, no verdict.
  EXPECT_EQ(two_agree(judge, p, 0.1, 0.9), ConvergenceJudge::Verdict::kNone);
  EXPECT_TRUE(p.running(3));
  EXPECT_EQ(two_agree(judge, p, 1.0, 4.0), ConvergenceJudge::Verdict::kAgreedWithoutSome);
  EXPECT_FALSE(p.running(3));
  EXPECT_FALSE(judge.converged());
  EXPECT_EQ(judge.missing(), std::vector<AgentId>{3});
}

// Agents start as their own neighbours are ready: one may fly (and trivially agree with itself)
// while the others still wait at their barrier. Those are not missing, and nothing is judged until
// they run; an agent that never leaves its barrier leaves the run unconverged, not "agreed".
TEST(ConvergenceJudge, AgentsStillAtTheirStartBarrierAreNotMissingAndHoldTheVerdict) {
  ConvergenceJudge judge(0.01, 0.5, 1.0, -1.0, FaultPlan{});
  Presence p({1, 2, 3}, 1.0);
  p.on_sample(sample(2, 1, 0.0, Vec3::Zero()), 0.0);
  records::GraphSnapshot agree;
  agree.set_agents(1);
  for (int k = 0; k <= 40; ++k) {
    const double t = 0.1 * k;
    p.on_sample(sample(1, static_cast<std::uint64_t>(k) + 1, t, Vec3::Zero(), Phase::kWaiting), t);
    p.on_sample(sample(3, static_cast<std::uint64_t>(k) + 1, t, Vec3::Zero(), Phase::kReady), t);
    p.on_sample(sample(2, static_cast<std::uint64_t>(k) + 2, t, Vec3::Zero()), t);
    EXPECT_EQ(ConvergenceJudge::Verdict::kNone, judge.update(t, agree, p)) << t;
  }
  agree.set_agents(3);
  for (const AgentId id : {1u, 3u}) p.on_sample(sample(id, 50, 4.1, Vec3::Zero()), 4.1);
  EXPECT_EQ(ConvergenceJudge::Verdict::kNone, judge.update(4.1, agree, p));
  hear(p, {1, 2, 3}, 4.6);
  EXPECT_EQ(ConvergenceJudge::Verdict::kConverged, judge.update(4.6, agree, p));
}

TEST(SeparationMonitor, JudgesEverySampleCountsEachViolationOnceAndForgetsTheDeparted) {
  SeparationMonitor m(1.0);
  EXPECT_FALSE(m.measured());
  // Two agents closing head-on at 1 m/s each, sampled every 20 ms at slightly different times:
  // agent 2's sample is moved to agent 1's instant by its velocity.
  for (int k = 0; k <= 100; ++k) {
    const double t = 0.02 * k;
    m.on_sample(1, Vec3(-2 + t, 0, 0), Vec3(1, 0, 0), t);
    m.on_sample(2, Vec3(2 - (t + 0.01), 0, 0), Vec3(-1, 0, 0), t + 0.01);
  }
  // Closest at t = 2 s (both at 0): measured on the samples, not on 10 Hz rows.
  EXPECT_NEAR(m.min_m(), 0.0, 1e-9);
  EXPECT_NEAR(m.min_t_s(), 2.0, 0.011);
  EXPECT_EQ(m.min_pair(), std::make_pair(AgentId{1}, AgentId{2}));
  EXPECT_EQ(m.violations(), 1u);  // below 1 m for many samples: one violation
  // Hovering at the boundary (in and out by less than kRearmM) is the same violation.
  m.on_sample(1, Vec3(-0.51, 0, 0), Vec3::Zero(), 2.5);
  m.on_sample(2, Vec3(0.51, 0, 0), Vec3::Zero(), 2.5);
  m.on_sample(1, Vec3(-0.48, 0, 0), Vec3::Zero(), 2.52);
  EXPECT_EQ(m.violations(), 1u);
  // Apart again, then close again: a second violation.
  m.on_sample(1, Vec3(-5, 0, 0), Vec3::Zero(), 3.0);
  m.on_sample(2, Vec3(5, 0, 0), Vec3::Zero(), 3.0);
  m.on_sample(1, Vec3(4.5, 0, 0), Vec3::Zero(), 3.02);
  EXPECT_EQ(m.violations(), 2u);
  // A departed agent's last position no longer counts: apart, agent 2 departs, agent 1 flies
  // through where 2 was.
  m.on_sample(1, Vec3(-5, 0, 0), Vec3::Zero(), 3.04);
  m.forget(2);
  m.on_sample(1, Vec3(5, 0, 0), Vec3::Zero(), 3.06);
  EXPECT_EQ(m.violations(), 2u);
  // A non-finite sample is ignored: it neither counts nor stays to be measured against.
  m.on_sample(3, Vec3(std::nan(""), 0, 0), Vec3::Zero(), 3.08);
  m.on_sample(4, Vec3(5.1, 0, 0), Vec3::Zero(), 3.08);  // close to agent 1: a third violation
  EXPECT_EQ(m.violations(), 3u);
  EXPECT_EQ(m.min_pair(), std::make_pair(AgentId{1}, AgentId{2}));
}

TEST(ConvergenceJudge, AnAgentHeldOffItsSlotByAvoidanceHasArrivedOnceItHoldsStill) {
  ConvergenceJudge judge(0.01, 0.5, 1.0, -1.0, FaultPlan{});
  Presence p({1, 2}, 1.0);
  for (AgentId id : {1u, 2u}) p.on_sample(sample(id, 1, 0.0, Vec3::Zero()), 0.0);
  records::GraphSnapshot g;
  g.set_agents(2);
  g.set_disagreement_m(0.001);
  g.set_spread_m(0.0);  // the held agents are not in the spread
  g.set_held_speed_mps(0.2);
  EXPECT_EQ(ConvergenceJudge::Verdict::kNone, judge.update(1.0, g, p));
  EXPECT_EQ(ConvergenceJudge::Verdict::kNone, judge.update(2.0, g, p));  // still moving
  g.set_held_speed_mps(0.005);  // below tolerance_m per second
  EXPECT_EQ(ConvergenceJudge::Verdict::kNone, judge.update(2.1, g, p));
  hear(p, {1, 2}, 2.6);
  EXPECT_EQ(ConvergenceJudge::Verdict::kConverged, judge.update(2.6, g, p));
}

TEST(GraphMetrics, HeldAgentsAreLeftOutOfTheSpreadFromTheSlots) {
  const std::vector<AgentId> ids{1, 2, 3};
  const Positions q(3, Vec3::Zero());
  const Positions p{Vec3(0.7, 0, 0), Vec3(-0.7, 0, 0), Vec3(5, 0.02, 0)};
  const Positions offsets{Vec3::Zero(), Vec3::Zero(), Vec3(5, 0, 0)};
  const std::vector<std::pair<AgentId, double>> none;
  const auto links = [&](int) -> const auto& { return none; };
  EXPECT_NEAR(measure_graph(0, ids, q, p, links, Vec3::Zero(), offsets).spread_m(), 0.7, 1e-12);
  EXPECT_NEAR(
      measure_graph(0, ids, q, p, links, Vec3::Zero(), offsets, {true, true, false}).spread_m(),
      0.02, 1e-12);
}

// Agents 1 (at x = 0) and 2 (at x = 2), unweighted, and `extra` of the scenario.
RunConfig two_agents(const std::string& name, const std::string& extra = "") {
  return resolve_scenario(parse_scenario_text(
      "name: \"" + name +
          "\"\nagents { id: 1 position { x: 0 } }\nagents { id: 2 position { x: 2 } }\n"
          "weight { policy: UNWEIGHTED }\n" +
          extra,
      name));
}

TEST(Recorder, FedWithMessagesWritesTheRunRecordAndASummary) {
  const RunConfig rc = two_agents("rec",
                                  "convergence { tolerance_m: 0.1 hold_s: 0.2 }\n"
                                  "faults { cut { a: 1 b: 2 start_s: 0.1 end_s: 0.2 } }\n");
  const std::filesystem::path dir = fresh_dir("qswarm-recorder");
  std::string text;
  {
    Recorder rec(rc, RunDir(dir), 1.0);
    std::int64_t wall = 1'000'000'000;
    for (int k = 0; k <= 50; ++k) {
      const double t = 0.02 * k;
      const double x = 1.0 - std::exp(-5.0 * t);  // both move to x = 1
      StateMessage a = sample(1, k + 1, t, Vec3(x, 0, 0)),
                   b = sample(2, k + 1, t, Vec3(2 - x, 0, 0));
      a.view.q0 = Vec3(0, 0, 0);
      b.view.q0 = Vec3(2, 0, 0);
      a.links = {{2, 1.0}};
      a.initial_links = {{2, 1.0}};
      b.links = {{1, 1.0}};
      b.initial_links = {{1, 1.0}};
      rec.on_sample(a, wall);
      rec.on_sample(b, wall);
      rec.tick(wall);
      wall += 20'000'000;
      if (rec.converged()) break;
    }
    EXPECT_TRUE(rec.converged());
    text = rec.finish("converged", 1.0);
    EXPECT_TRUE(rec.complete()) << rec.failed_file();
    EXPECT_EQ(rec.summary().edges_initial_size(), 1);
    EXPECT_EQ(rec.summary().agents_size(), 2);
    EXPECT_EQ(rec.summary().joins(), 2u);
  }
  EXPECT_NE(text.find("CONVERGED"), std::string::npos) << text;
  for (const char* f : {"telemetry.csv", "graph.csv", "events.csv", "records.pb", "summary.json"})
    EXPECT_GT(std::filesystem::file_size(dir / f), 20u) << f;
  std::ifstream ev(dir / "events.csv");
  std::stringstream all;
  all << ev.rdbuf();
  for (const char* kind : {",join,", ",cut,", ",cut_end,", ",converged,", ",end,"})
    EXPECT_NE(all.str().find(kind), std::string::npos) << kind << " in\n" << all.str();
  std::filesystem::remove_all(dir);
}

TEST(Recorder, AStampFarAheadOfTheSwarmsClockNeverMovesTheRunsClock) {
  // Two agents fly at 50 Hz for 1 s; mid-run a sample of agent 2's id stamped a million seconds
  // ahead arrives (a forger's, or a relay's from the future), then another 10 s ahead. Neither
  // moves the run's clock: no early end, no rows at their stamps; refused, counted, said once.
  const RunConfig rc = two_agents("ahead", "duration_s: 30\n");
  const std::filesystem::path dir = fresh_dir("qswarm-ahead");
  records::Summary s;
  {
    Recorder rec(rc, RunDir(dir), 1.0);
    std::int64_t wall = 1'000'000'000;
    for (int k = 0; k <= 50; ++k) {
      const double t = 0.02 * k;
      rec.on_sample(sample(1, k + 1, t, Vec3(0, 0, 0)), wall);
      rec.on_sample(sample(2, k + 1, t, Vec3(2, 0, 0)), wall);
      if (k == 20) rec.on_sample(sample(2, 1000, 1e6, Vec3(50, 0, 0)), wall);
      if (k == 30)
        rec.on_sample(sample(2, 1001, t + 10.0, Vec3(50, 0, 0)), wall);  // past the slack
      rec.tick(wall);
      EXPECT_LE(rec.time_s(), t + 1e-9) << k;
      EXPECT_FALSE(rec.duration_reached()) << k;
      wall += 20'000'000;
    }
    rec.finish("duration", 1.0);
    s = rec.summary();
  }
  EXPECT_EQ(s.implausible_samples(), 2u);
  std::ifstream ev(dir / "events.csv");
  std::stringstream all;
  all << ev.rdbuf();
  const std::string said = ",implausible_sample,2,";
  ASSERT_NE(all.str().find(said), std::string::npos) << all.str();
  EXPECT_EQ(all.str().find(said, all.str().find(said) + 1), std::string::npos) << "said twice";
  for (const auto& row : std::vector<std::string>{"telemetry.csv", "graph.csv"}) {
    std::ifstream in(dir / row);
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) EXPECT_LT(std::atof(line.c_str()), 2.0) << row << ": " << line;
  }
  std::filesystem::remove_all(dir);
}

TEST(Recorder, TheHostsEachAgentFlewOnAreRecordedInOrderAndAFlappingOneIsNotFollowed) {
  const RunConfig rc = two_agents("hosts");
  const std::filesystem::path dir = fresh_dir("qswarm-hosts");
  std::string text;
  records::Summary s;
  {
    Recorder rec(rc, RunDir(dir), 1.0);
    std::int64_t wall = 1'000'000'000;
    for (int k = 0; k < 60; ++k) {
      StateMessage a = sample(1, k + 1, 0.02 * k, Vec3(0, 0, 0)),
                   b = sample(2, k + 1, 0.02 * k, Vec3(2, 0, 0));
      // Agent 1 moves from host a to host b at its 20th sample (a restart elsewhere); agent 2's
      // host changes at every sample, as no restart does.
      a.host = k < 20 ? "a/10.0.0.1" : "b/10.0.0.2";
      b.host = "h" + std::to_string(k) + "/10.0.1." + std::to_string(k);
      rec.on_sample(a, wall);
      rec.on_sample(b, wall);
      rec.tick(wall);
      wall += 20'000'000;
    }
    text = rec.finish("duration", 1.2);
    s = rec.summary();
  }
  ASSERT_EQ(s.agents_size(), 2);
  EXPECT_EQ(std::vector<std::string>(s.agents(0).hosts().begin(), s.agents(0).hosts().end()),
            (std::vector<std::string>{"a/10.0.0.1", "b/10.0.0.2"}));
  EXPECT_EQ(s.agents(1).hosts_size(), static_cast<int>(Recorder::kMaxHostsPerAgent));
  std::ifstream ev(dir / "events.csv");
  std::stringstream all;
  all << ev.rdbuf();
  EXPECT_NE(all.str().find(",host,1,\"flies on b/10.0.0.2\""), std::string::npos) << all.str();
  const std::string capped = "on more than 16 hosts";
  ASSERT_NE(all.str().find(capped), std::string::npos) << all.str();
  EXPECT_EQ(all.str().find(capped, all.str().find(capped) + 1), std::string::npos) << "said twice";
  EXPECT_NE(text.find("hosts 2: b/10.0.0.2 (1 agent)"), std::string::npos) << text;
  std::filesystem::remove_all(dir);
}

TEST(Recorder, AnAgentHeardOnlyAtItsStartBarrierIsNamedAsNeverRan) {
  // Given a run whose duration runs out while agent 2 still waits at its start barrier
  const RunConfig rc = resolve_scenario(parse_scenario_text(
      "name: \"barrier\"\nagents { id: 1 position { x: 0 } }\nagents { id: 2 position { x: 2 } }\n"
      "agents { id: 3 position { x: 4 } }\nagents { id: 4 position { x: 6 } }\n"
      "weight { policy: UNWEIGHTED }\n",
      "barrier"));
  // An announcement at the barrier: its law has not ticked
  const auto waiting = [](AgentId id, std::uint64_t seq, Phase phase) {
    StateMessage m = sample(id, seq, 0.0, Vec3(2.0 * (id - 1), 0, 0), phase);
    m.view.seq = 0;
    return m;
  };
  const std::filesystem::path dir = fresh_dir("qswarm-never-ran");
  std::string text;
  records::Summary summary;
  {
    Recorder rec(rc, RunDir(dir), 1.0);
    std::int64_t wall = 1'000'000'000;
    for (int k = 0; k < 20; ++k) {
      const auto seq = static_cast<std::uint64_t>(k + 1);
      rec.on_sample(sample(1, seq, 0.02 * k, Vec3(0, 0, 0)), wall);
      rec.on_sample(waiting(2, seq, Phase::kReady), wall);
      // Agent 3 waited at the barrier too, then ran
      rec.on_sample(k < 10 ? waiting(3, seq, Phase::kWaiting)
                           : sample(3, seq, 0.02 * (k - 10), Vec3(4, 0, 0)),
                    wall);
      rec.on_sample(waiting(4, seq, Phase::kReady), wall);
      rec.tick(wall);
      wall += 20'000'000;
    }
    rec.on_sample(waiting(2, 21, Phase::kStopping), wall);
    // Agent 4 ran three ticks, none of them a record's, and was stopped: its goodbye says so
    StateMessage bye = waiting(4, 24, Phase::kStopping);
    bye.view.seq = 3;
    rec.on_sample(bye, wall);
    text = rec.finish("duration", 1.0);
    summary = rec.summary();
  }
  std::filesystem::remove_all(dir);
  // Then the record names agent 2, and only it
  EXPECT_FALSE(summary.converged());
  ASSERT_EQ(summary.never_ran_agents_size(), 1);
  EXPECT_EQ(summary.never_ran_agents(0), 2u);
  EXPECT_NE(text.find("NEVER RAN: 1 agent(s) were heard only at their start barrier: 2\n"),
            std::string::npos)
      << text;
}

// Two agents that agree while agent 1 reports that agent 2's samples come from two writers at
// once (a plain run with an impersonator), and the supervisor's own transport refused a sample of
// agent 1 from the future: both are named once, and the run that agreed has not converged.
struct ForgedRun {
  std::string text, events, end_reason;
  records::Summary summary;
  bool converged = false;
};

ForgedRun fly_with_suspects(std::uint8_t reported_by_agent_1) {
  const RunConfig rc = two_agents("forged", "convergence { tolerance_m: 0.1 hold_s: 0.2 }\n");
  const std::filesystem::path dir = fresh_dir("qswarm-forged");
  ForgedRun out;
  {
    Recorder rec(rc, RunDir(dir), 1.0);
    std::int64_t wall = 1'000'000'000;
    for (int k = 0; k <= 100 && out.end_reason.empty(); ++k) {
      const double t = 0.02 * k;
      const double x = 1.0 - std::exp(-5.0 * t);
      StateMessage a = sample(1, k + 1, t, Vec3(x, 0, 0)),
                   b = sample(2, k + 1, t, Vec3(2 - x, 0, 0));
      a.view.q0 = Vec3(0, 0, 0);
      b.view.q0 = Vec3(2, 0, 0);
      a.links = a.initial_links = {{2, 1.0}};
      b.links = b.initial_links = {{1, 1.0}};
      // Agent 999 is not in the scenario: a report naming it is not recorded.
      if (k >= 10) a.suspects = {{2, reported_by_agent_1}, {999, kTwoWriters}};
      rec.on_sample(a, wall);
      rec.on_sample(b, wall);
      if (k == 20) rec.note_suspects({{1, kFutureIncarnation}}, 0);
      rec.tick(wall);
      wall += 20'000'000;
      out.end_reason = rec.end_reason_if_over();
    }
    const std::vector<std::string> notes = rec.take_notes();
    EXPECT_EQ(notes.size(), static_cast<std::size_t>(1 + __builtin_popcount(reported_by_agent_1)));
    EXPECT_TRUE(rec.take_notes().empty());
    out.converged = rec.converged();
    out.text = rec.finish(out.end_reason, 2.0);
    out.summary = rec.summary();
  }
  std::ifstream ev(dir / "events.csv");
  std::stringstream all;
  all << ev.rdbuf();
  out.events = all.str();
  std::filesystem::remove_all(dir);
  return out;
}

TEST(Recorder, AnAgentsSamplesFromTwoWritersAreNamedAndTheRunThatAgreedDoesNotConverge) {
  const ForgedRun r = fly_with_suspects(kTwoWriters);
  EXPECT_FALSE(r.converged);
  EXPECT_FALSE(r.summary.converged());
  EXPECT_EQ(r.summary.convergence_time_s(), -1.0);
  EXPECT_NE(r.end_reason.find("agreed, but the samples of agent 2 came from two writers"),
            std::string::npos)
      << r.end_reason;
  EXPECT_NE(r.end_reason.find("noticed by 1)"), std::string::npos) << r.end_reason;
  ASSERT_EQ(r.summary.forgeries_size(), 2);
  EXPECT_EQ(r.summary.forgeries(0).agent(), 1u);
  EXPECT_EQ(r.summary.forgeries(0).kind(), "future_incarnation");
  EXPECT_EQ(r.summary.forgeries(0).noticed_by(0), 0u);  // the supervisor
  EXPECT_EQ(r.summary.forgeries(1).agent(), 2u);
  EXPECT_EQ(r.summary.forgeries(1).kind(), "two_writers");
  EXPECT_EQ(r.summary.forgeries(1).noticed_by(0), 1u);
  EXPECT_NEAR(r.summary.forgeries(1).first_t_s(), 0.2, 0.03);
  // Named once each, however often reported; the agreement is an event, not "converged".
  std::size_t forgery_lines = 0;
  for (std::size_t at = r.events.find(",forgery,"); at != std::string::npos;
       at = r.events.find(",forgery,", at + 1))
    ++forgery_lines;
  EXPECT_EQ(forgery_lines, 2u) << r.events;
  EXPECT_NE(r.events.find(",agreed_forged,"), std::string::npos) << r.events;
  EXPECT_EQ(r.events.find(",converged,"), std::string::npos) << r.events;
  EXPECT_NE(r.text.find("NOT CONVERGED"), std::string::npos) << r.text;
  EXPECT_NE(r.text.find("FORGED: agent 2: two_writers"), std::string::npos) << r.text;
}

TEST(Recorder, ForgeriesThatWereRefusedAreNamedButDoNotUnmakeTheConvergence) {
  // A sequence jump and a certificate bound elsewhere are refused where they arrive.
  const ForgedRun r = fly_with_suspects(kSequenceJump | kBoundElsewhere);
  EXPECT_TRUE(r.converged);
  EXPECT_TRUE(r.summary.converged());
  EXPECT_EQ(r.end_reason, "converged");
  EXPECT_EQ(r.summary.forgeries_size(), 3);
  EXPECT_NE(r.events.find("sequence_jump"), std::string::npos) << r.events;
  EXPECT_NE(r.events.find("bound_elsewhere"), std::string::npos) << r.events;
}

}  // namespace
}  // namespace qswarm
