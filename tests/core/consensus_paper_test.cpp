// The paper's section 2 examples: agreement points, Laplacians and spectra, time-varying topology.
#include <gtest/gtest.h>

#include "common/core/graph.hpp"
#include "common/sim/lockstep_laws.hpp"
#include "tests/core/paper_data.hpp"

namespace qswarm {
namespace {

void expect_vec_near(const Vec3& a, const Vec3& b, double tol) {
  EXPECT_NEAR(a.x(), b.x(), tol);
  EXPECT_NEAR(a.y(), b.y(), tol);
  EXPECT_NEAR(a.z(), b.z(), tol);
}

void expect_spectrum(const Eigen::MatrixXd& L, const std::vector<double>& expected, double tol) {
  const Spectrum s = analyze(L);
  ASSERT_EQ(s.eigenvalues.size(), static_cast<long>(expected.size()));
  for (size_t k = 0; k < expected.size(); ++k) EXPECT_NEAR(s.eigenvalues[k], expected[k], tol) << k;
}

LockstepConfig paper_swarm(const Positions& q0, std::string kind, WeightPolicy w,
                           TopologyPolicy topo, std::vector<std::pair<AgentId, AgentId>> edges) {
  LockstepConfig cfg;
  for (size_t i = 0; i < q0.size(); ++i) cfg.agents.push_back({static_cast<AgentId>(i + 1), q0[i]});
  cfg.law.law = kind;
  cfg.law.weight.policy = w;
  cfg.law.topology.policy = topo;
  cfg.law.topology.edges = std::move(edges);
  cfg.law.topology.threshold_m = 12.5;
  return cfg;
}

TEST(PaperAgreement, AgreementPointsAreTheInitialAverages) {
  // Paper: (10.25, 9.75, 29.25), (9, 12.75, 30.25), (15.25, 10.25, 31).
  expect_vec_near(average(paper::kUnweightedQ0), paper::kUnweightedAgreement, 1e-12);
  expect_vec_near(average(paper::kWeightedQ0), paper::kWeightedAgreement, 1e-12);
  expect_vec_near(average(paper::kTimeVaryingQ0), paper::kTimeVaryingAgreement, 1e-12);
}

TEST(PaperAgreement, UnweightedSpectra) {
  // Paper 2.6.1: eigenvalues {0, 1, 3, 4} for L_1 and {0, 0.586, 2, 3.414} for L_2.
  const Eigen::MatrixXd L1 = laplacian(4, paper::to_index_edges(paper::kGraph1));
  Eigen::MatrixXd L1_paper(4, 4);
  L1_paper << 1, -1, 0, 0, -1, 3, -1, -1, 0, -1, 2, -1, 0, -1, -1, 2;
  EXPECT_TRUE(L1.isApprox(L1_paper));
  expect_spectrum(L1, {0, 1, 3, 4}, 1e-12);
  expect_spectrum(laplacian(4, paper::to_index_edges(paper::kGraph2)), {0, 0.586, 2, 3.414}, 5e-4);
}

TEST(PaperAgreement, DistanceWeightedLaplacianAndSpectrum) {
  // Paper 2.7.1: L_2 printed to 4 decimals, eigenvalues {0, 13.060, 42.248, 62.558}.
  const Eigen::MatrixXd L =
      laplacian(4, paper::to_index_edges(paper::kGraph1, &paper::kWeightedQ0));
  Eigen::MatrixXd printed(4, 4);
  printed << 12.8062, -12.8062, 0, 0, -12.8062, 41.9036, -20.3224, -8.7750, 0, -20.3224, 37.3518,
      -17.0294, 0, -8.7750, -17.0294, 25.8044;
  EXPECT_LT((L - printed).cwiseAbs().maxCoeff(), 5e-5);
  expect_spectrum(L, {0, 13.060, 42.248, 62.558}, 5e-4);
}

TEST(PaperAgreement, TimeVaryingInitialLaplacianMatchesPrintedMatrix) {
  // Paper 2.7.2: L_{2i} printed to 4 decimals. The paper prints lambda_2 = 6.234, but the
  // eigenvalues of its own printed matrix (and of the matrix built from its positions, which agrees
  // with the print to 4 decimals) are {0, 6.240, 19.385, 37.655}: we match the matrix, since the
  // other two printed eigenvalues agree with it and 6.234 is not an eigenvalue of either.
  const Eigen::MatrixXd L =
      laplacian(4, paper::to_index_edges(paper::kGraph2, &paper::kTimeVaryingQ0));
  Eigen::MatrixXd printed(4, 4);
  printed << 23.0375, 0, -12.0830, -10.9545, 0, 8.6023, -8.6023, 0, -12.0830, -8.6023, 20.6854, 0,
      -10.9545, 0, 0, 10.9545;
  EXPECT_LT((L - printed).cwiseAbs().maxCoeff(), 5e-5);
  expect_spectrum(L, {0, 6.240, 19.385, 37.655}, 5e-4);
  expect_spectrum(printed, {0, 6.240, 19.385, 37.655}, 5e-4);
  EXPECT_GT(std::abs(analyze(L).lambda2 - 6.234), 5e-3);
}

class TimeVaryingRun : public ::testing::TestWithParam<std::string> {};

TEST_P(TimeVaryingRun, AddsEdgesEndsFullyConnectedAndMeetsAtTheAverage) {
  // Given the paper's time-varying example: distance weights, sticky proximity (threshold 12.5 m:
  // the paper does not state one; any value in [12.083, 15.937) gives its initial graph).
  LockstepLaws swarm(paper_swarm(paper::kTimeVaryingQ0, GetParam(), WeightPolicy::kDistance,
                                 TopologyPolicy::kStickyProximity, {}));
  ASSERT_EQ(swarm.edges().size(), 3u);  // the initial graph is the paper's: 1-3, 1-4, 2-3
  size_t max_edges = 3;
  std::vector<double> edge_added_at;
  // When it runs for 40 s at the default 50 Hz
  while (swarm.time_s() < 40.0) {
    swarm.step();
    if (swarm.edges().size() > max_edges) {
      max_edges = swarm.edges().size();
      edge_added_at.push_back(swarm.time_s());
    }
  }
  // Then edges were added at runtime, it ends on the complete graph K4, and meets at q*.
  ASSERT_FALSE(edge_added_at.empty());
  EXPECT_GT(edge_added_at.front(), 0.0);  // links formed at runtime, from motion
  EXPECT_EQ(swarm.edges().size(), 6u);
  EXPECT_EQ(analyze(laplacian(4, swarm.edges())).components, 1);
  for (const Vec3& q : swarm.states()) expect_vec_near(q, paper::kTimeVaryingAgreement, 1e-2);
  expect_vec_near(average(swarm.states()), paper::kTimeVaryingAgreement, 1e-6);
}

INSTANTIATE_TEST_SUITE_P(BothLaws, TimeVaryingRun,
                         ::testing::Values(std::string("laplacian"), std::string("edge-flow")),
                         [](const ::testing::TestParamInfo<std::string>& p) {
                           return p.param == std::string("laplacian") ? std::string("laplacian")
                                                                      : std::string("edge_flow");
                         });

}  // namespace
}  // namespace qswarm
