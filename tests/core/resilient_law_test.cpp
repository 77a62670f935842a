// The resilient law (W-MSR) and the graph condition it needs, against one insider that lies.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "common/core/graph.hpp"
#include "common/core/update_law.hpp"
#include "common/sim/lockstep_laws.hpp"

namespace qswarm {
namespace {

std::vector<Edge> complete(int n) {
  std::vector<Edge> e;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) e.push_back({i, j, 1.0});
  return e;
}

std::vector<Edge> ring(int n) {
  std::vector<Edge> e;
  for (int i = 0; i < n; ++i) e.push_back({std::min(i, (i + 1) % n), std::max(i, (i + 1) % n)});
  return e;
}

TEST(Robustness, TheCompleteGraphOnSevenToleratesOneLiarAndARingNone) {
  // K_n is (ceil(n/2), n)-robust; a cycle is 1-robust only (two arcs each reach out by 1 edge).
  EXPECT_TRUE(is_rs_robust(7, complete(7), 2, 2));
  EXPECT_TRUE(is_rs_robust(7, complete(7), 4, 7));
  EXPECT_FALSE(is_rs_robust(7, complete(7), 5, 1));
  EXPECT_TRUE(is_rs_robust(7, ring(7), 1, 1));
  EXPECT_FALSE(is_rs_robust(7, ring(7), 2, 2));
  const ResilienceCheck k7 = check_resilience(7, complete(7), 1);
  EXPECT_TRUE(k7.ok());
  EXPECT_EQ(k7.min_degree, 6);
  // F = 2 needs degree 5 and (3,3)-robustness: K7 has both (ceil(7/2) = 4 >= 3).
  EXPECT_TRUE(check_resilience(7, complete(7), 2).ok());
  // F = 3: degree 7 needed, K7 has 6.
  EXPECT_FALSE(check_resilience(7, complete(7), 3).degree_ok);
  const ResilienceCheck r7 = check_resilience(7, ring(7), 1);
  EXPECT_FALSE(r7.degree_ok);
  EXPECT_EQ(r7.robust, false);
}

TEST(Robustness, EnoughDegreeIsNotEnough) {
  // Two K4 joined by one edge: every vertex has degree >= 3 = 2F+1 for F = 1, but the halves
  // reach each other through one edge only: not (2,2)-robust, and a liar on the bridge splits it.
  std::vector<Edge> e;
  for (int base : {0, 4})
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) e.push_back({base + i, base + j});
  e.push_back({3, 4});
  const ResilienceCheck c = check_resilience(8, e, 1);
  EXPECT_TRUE(c.degree_ok);
  EXPECT_EQ(c.robust, false);
  EXPECT_FALSE(c.ok());
}

TEST(Robustness, LargeGraphsAreNotDecidedExhaustively) {
  EXPECT_FALSE(check_resilience(kMaxExactRobustness + 1, complete(kMaxExactRobustness + 1), 1)
                   .robust.has_value());
  EXPECT_THROW(is_rs_robust(kMaxExactRobustness + 1, {}, 1, 1), std::invalid_argument);
}

LawConfig wmsr(int f) {
  LawConfig c;
  c.law = std::string("w-msr");
  c.params["f"] = f;
  c.weight.policy = WeightPolicy::kUnweighted;
  // Everyone within 1000 km: the complete graph, whatever anyone claims.
  c.topology.policy = TopologyPolicy::kStickyProximity;
  c.topology.threshold_m = 1e6;
  return c;
}

NeighborView view(AgentId id, const Vec3& q) {
  NeighborView v;
  v.id = id;
  v.q = q;
  v.q0 = q;
  v.total_weight = 1.0;
  v.seq = 1;
  return v;
}

TEST(WmsrLaw, DropsTheFExtremesOnEachSideOfItsOwnValuePerCoordinate) {
  // Own x = 0; neighbours at -3, -1, 2, 50 (x) and all at y = z = 0. F = 1 drops -3 and 50: the
  // step moves toward the mean of -1 and 2 only, i.e. to the right, never toward 50's pull.
  WmsrLaw law(1, Vec3::Zero(), wmsr(1));
  const std::vector<NeighborView> n = {view(2, {-3, 0, 0}), view(3, {-1, 0, 0}), view(4, {2, 0, 0}),
                                       view(5, {50, 0, 0})};
  law.observe(n);
  law.step(0.02, n);
  EXPECT_GT(law.state().x(), 0.0);
  EXPECT_LT(law.state().x(), 2.0 * 0.3);  // at most s of the way to the kept values' mean
  EXPECT_EQ(law.state().y(), 0.0);
  EXPECT_EQ(law.trimmed(), 2u);  // y and z: every value equals its own, none trimmed
}

TEST(WmsrLaw, WithFewerValuesOnOneSideThanFItDropsAllOfThem) {
  // Own x = 0; one neighbour above (10), three below: F = 2 drops the one above (all of them) and
  // the two lowest below; the agent moves down, toward -1 only.
  WmsrLaw law(1, Vec3::Zero(), wmsr(2));
  const std::vector<NeighborView> n = {view(2, {10, 0, 0}), view(3, {-1, 0, 0}),
                                       view(4, {-5, 0, 0}), view(5, {-9, 0, 0})};
  law.observe(n);
  law.step(0.02, n);
  EXPECT_LT(law.state().x(), 0.0);
  EXPECT_GT(law.state().x(), -1.0);
}

TEST(WmsrLaw, WithoutLiarsItStillAgrees) {
  LockstepConfig cfg;
  cfg.agents = LockstepLaws::random_agents(7, 11, 20.0);
  cfg.law = wmsr(1);
  LockstepLaws swarm(cfg);
  EXPECT_TRUE(swarm.run_until_converged(1e-6, 200.0));
}

// Does every honest agent end inside the honest initial values' bounding box (per coordinate)?
bool inside_honest_box(const LockstepLaws& s, double slack_m) {
  return outside_box_m(s.honest_states(), s.honest_initial_states()) <= slack_m;
}

struct Attack {
  const char* name;
  Liar liar;
};

std::vector<Attack> attacks() {
  const Vec3 far(1000, 1000, 1000);
  Liar constant{7, Liar::Kind::kConstant, far};
  Liar drift{7, Liar::Kind::kDrift, Vec3(0.5, 0.5, 0.5)};
  Liar split{7, Liar::Kind::kSplit, far};
  return {{"constant", constant}, {"drift", drift}, {"split", split}};
}

// One insider (agent 7) of a 7-agent complete graph lies for 120 s; the honest six run `law`.
LockstepLaws attacked(const std::string& law, const Liar& liar) {
  LockstepConfig cfg;
  cfg.agents = LockstepLaws::random_agents(7, 5, 20.0);
  cfg.law = wmsr(1);
  cfg.law.law = law;
  if (law != "w-msr") cfg.law.params.clear();  // F is W-MSR's alone
  cfg.liar = liar;
  LockstepLaws s(cfg);
  while (s.time_s() < 120.0) s.step();
  return s;
}

TEST(WmsrLaw, OneLiarOnSevenCannotDragTheHonestOutOfTheirInitialRange) {
  for (const Attack& a : attacks()) {
    SCOPED_TRACE(a.name);
    const LockstepLaws s = attacked(std::string("w-msr"), a.liar);
    EXPECT_TRUE(inside_honest_box(s, 1e-9));
    EXPECT_LT(disagreement(s.honest_states()), 1e-6);  // and they agree
  }
}

TEST(WmsrLaw, TheSameLiarDragsTheLawsThatTrustEveryone) {
  // Side by side: the laws that take every neighbour's value as given follow the liar out of the
  // honest range (drift: 0.5 m/s for 120 s, far beyond the 20 m box).
  for (const char* law : {"laplacian", "edge-flow"}) {
    for (const Attack& a : attacks()) {
      SCOPED_TRACE(std::string(law) + " / " + a.name);
      const LockstepLaws s = attacked(law, a.liar);
      EXPECT_FALSE(inside_honest_box(s, 1.0));
    }
  }
}

TEST(Robustness, OutsideTheBoxIsMeasuredPerCoordinate) {
  const Positions box = {{0, 0, 0}, {10, 2, 4}};
  EXPECT_EQ(outside_box_m({{5, 1, 2}, {10, 0, 4}}, box), 0.0);
  // (13, 6, 4): 3 beyond x, 4 beyond y: 5 m from the box, though inside the span of each axis' z.
  EXPECT_DOUBLE_EQ(outside_box_m({{5, 1, 2}, {13, 6, 4}}, box), 5.0);
  EXPECT_DOUBLE_EQ(outside_box_m({{-1, 1, 2}}, box), 1.0);
  EXPECT_EQ(outside_box_m({{1e9, 0, 0}}, {}), 0.0);
}

// The table of docs/resilience.md and what `swarm resilience` writes (numbers.csv) come from
// tests/core/insider_seven_expected.csv, which this test holds the core law to: the same
// scenario (scenarios/insider_seven.txtpb is these seven agents), law and attacks, 120 s.
TEST(InsiderTable, TheLockstepLawsGiveTheNumbersSwarmResilienceDraws) {
  std::ifstream in(std::string(QSWARM_SOURCE_DIR) + "/tests/core/insider_seven_expected.csv");
  ASSERT_TRUE(in) << "tests/core/insider_seven_expected.csv";
  std::string line;
  std::getline(in, line);
  ASSERT_EQ(line, "law,attack,outside_m,max_outside_m,disagreement_m,mean_x,mean_y,mean_z");
  int rows = 0;
  while (std::getline(in, line)) {
    std::istringstream row(line);
    std::string law, attack, field;
    std::getline(row, law, ',');
    std::getline(row, attack, ',');
    std::vector<double> want;
    while (std::getline(row, field, ',')) want.push_back(std::stod(field));
    ASSERT_EQ(want.size(), 6u) << line;
    SCOPED_TRACE(law + " / " + attack);
    Liar liar;
    for (const Attack& a : attacks())
      if (attack == a.name) liar = a.liar;
    ASSERT_EQ(liar.id, 7u) << "unknown attack " << attack;
    LockstepConfig cfg;
    cfg.agents = LockstepLaws::random_agents(7, 5, 20.0);
    cfg.law = wmsr(1);
    cfg.law.law = law;
    if (law != "w-msr") cfg.law.params.clear();  // F is W-MSR's alone
    cfg.liar = liar;
    LockstepLaws s(cfg);
    double most_outside = 0.0;
    for (;;) {
      most_outside =
          std::max(most_outside, outside_box_m(s.honest_states(), s.honest_initial_states()));
      if (s.time_s() >= 120.0) break;
      s.step();
    }
    const Vec3 mean = average(s.honest_states());
    const std::vector<double> got = {outside_box_m(s.honest_states(), s.honest_initial_states()),
                                     most_outside,
                                     disagreement(s.honest_states()),
                                     mean.x(),
                                     mean.y(),
                                     mean.z()};
    for (std::size_t k = 0; k < got.size(); ++k)
      EXPECT_NEAR(got[k], want[k], 1e-9 + 1e-9 * std::abs(want[k])) << "column " << k + 2;
    ++rows;
  }
  EXPECT_EQ(rows, 9);  // three laws, three attacks
}

}  // namespace
}  // namespace qswarm
