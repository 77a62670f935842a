// Seeded random-mutation fuzzing of the two inputs a stranger controls: a scenario file (from a
// person) and a state sample (from the network). Whatever the bytes, loading either ends in a
// value that honours its invariants or a clean refusal: never a crash, a hang or another exception.
// Runs a bounded number of mutations (CI runs it under ASan+UBSan too); the corpus is
// scenarios/*.txtpb, scenarios/paper/*.txtpb plus tests/fuzz/corpus. QSWARM_FUZZ_ITERATIONS raises
// the count by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "common/scenario/scenario.hpp"
#include "common/transport/port_plan.hpp"
#include "common/transport/sample_gate.hpp"

namespace qswarm {
namespace {

std::vector<std::string> corpus() {
  std::vector<std::string> out;
  for (const char* dir : {"/scenarios", "/scenarios/paper", "/tests/fuzz/corpus"}) {
    for (const auto& e :
         std::filesystem::directory_iterator(std::string(QSWARM_SOURCE_DIR) + dir)) {
      if (e.path().extension() != ".txtpb") continue;
      std::ifstream in(e.path());
      std::stringstream s;
      s << in.rdbuf();
      out.push_back(s.str());
    }
  }
  return out;
}

int iterations(int dflt) {
  const char* env = std::getenv("QSWARM_FUZZ_ITERATIONS");
  return env ? std::max(1, std::atoi(env)) : dflt;
}

// Byte and token mutations: flip, insert, erase, duplicate a span, splice numbers that matter.
std::string mutate(std::string s, std::mt19937_64& rng) {
  static const std::vector<std::string> kTokens = {
      "nan",      "-nan", "inf",        "-inf", "1e308",  "-1e308",
      "0",        "-0",   "4294967296", "-1",   "1e-320", "18446744073709551616",
      "{",        "}",    "\"",         "\\",   ":",      "agents { id: 7 }",
      "faults {", "\n"};
  std::uniform_int_distribution<int> op(0, 5);
  const int n = 1 + static_cast<int>(rng() % 4);
  for (int k = 0; k < n; ++k) {
    const std::size_t at = s.empty() ? 0 : rng() % s.size();
    switch (op(rng)) {
      case 0:
        if (!s.empty()) s[at] = static_cast<char>(rng() % 256);
        break;
      case 1:
        s.insert(at, 1, static_cast<char>(rng() % 256));
        break;
      case 2:
        if (!s.empty()) s.erase(at, 1 + rng() % 16);
        break;
      case 3:
        if (!s.empty()) s.insert(at, s.substr(rng() % s.size(), 1 + rng() % 64));
        break;
      default: {
        // Replace a number with a hostile one.
        const std::size_t digit = s.find_first_of("0123456789", at);
        const std::string& tok = kTokens[rng() % kTokens.size()];
        if (digit != std::string::npos) {
          const std::size_t end = s.find_first_not_of("0123456789.e-+", digit);
          s.replace(digit, (end == std::string::npos ? s.size() : end) - digit, tok);
        } else {
          s.insert(at, tok);
        }
      }
    }
  }
  return s;
}

void expect_invariants(const RunConfig& rc) {
  ASSERT_FALSE(rc.agents.empty());
  ASSERT_LE(rc.agents.size(), kMaxSwarmAgents);
  for (const AgentSpec& a : rc.agents) {
    ASSERT_NE(a.id, 0u);
    ASSERT_TRUE(a.position_W.allFinite());
    ASSERT_TRUE(std::isfinite(a.yaw_rad));
  }
  for (const double v :
       {rc.agent.physics_hz, rc.agent.consensus_hz, rc.judge.duration_s, rc.judge.tolerance_m,
        rc.agent.neighbor_timeout_s, rc.agent.law.gain, rc.agent.law.weight.scale}) {
    ASSERT_TRUE(std::isfinite(v) && v > 0.0) << v;
  }
  const double ratio = rc.agent.physics_hz / rc.agent.consensus_hz;
  ASSERT_NEAR(ratio, std::round(ratio), 1e-6 * ratio);
  ASSERT_LE(rc.transport.domain_id, PortPlan::kMaxDomain);  // the port plan's last domain
  for (const auto& k : rc.faults.kill) ASSERT_TRUE(std::isfinite(k.at_s) && k.at_s > 0.0);
  for (const auto& d : rc.faults.delay) ASSERT_TRUE(std::isfinite(d.mean_s + d.jitter_s));
}

TEST(Fuzz, ScenarioLoadingRefusesOrHonoursItsInvariants) {
  const std::vector<std::string> seeds = corpus();
  ASSERT_GE(seeds.size(), 10u);
  std::mt19937_64 rng(20261121);
  int accepted = 0, refused = 0;
  const int n = iterations(4000);
  for (int i = 0; i < n; ++i) {
    const std::string text = mutate(seeds[rng() % seeds.size()], rng);
    try {
      const RunConfig rc = resolve_scenario(parse_scenario_text(text, "fuzz"));
      expect_invariants(rc);
      if (::testing::Test::HasFatalFailure()) {
        ADD_FAILURE() << "mutation " << i << ":\n" << text;
        return;
      }
      ++accepted;
    } catch (const ScenarioError&) {
      ++refused;
    }
  }
  // Both outcomes occur: the mutations reach the resolver, not only the parser.
  EXPECT_GT(accepted, n / 50);
  EXPECT_GT(refused, n / 50);
  std::printf("fuzz: %d scenarios accepted, %d refused\n", accepted, refused);
}

double hostile(std::mt19937_64& rng) {
  static const double kValues[] = {std::nan(""), INFINITY, -INFINITY, 1e308, -1e308, 0.0, -0.0,
                                   1e-320,       1e6,      1e9,       1e7,   -1.0,   0.5, 1.0};
  return rng() % 3 == 0 ? kValues[rng() % std::size(kValues)]
                        : std::uniform_real_distribution<double>(-2e6, 2e6)(rng);
}

TEST(Fuzz, TheSampleGateRefusesEveryHostileSampleAndAdmitsOnlySaneOnes) {
  std::mt19937_64 rng(7);
  SampleGate gate;
  int admitted = 0, refused = 0;
  const int n = iterations(20000);
  for (int i = 0; i < n; ++i) {
    StateMessage m;
    m.view.id = static_cast<AgentId>(rng() % 4);
    m.seq = rng() % 1000;
    m.incarnation = static_cast<std::int64_t>(rng() % 3);
    m.stamp_s = hostile(rng);
    m.phase = static_cast<Phase>(rng() % 6);
    m.mode = static_cast<PoseKind>(rng() % 3);
    m.view.q = Vec3(hostile(rng), hostile(rng), hostile(rng)) * (rng() % 2 ? 1e-3 : 1.0);
    m.view.q0 = Vec3(hostile(rng), 0, 0) * 1e-3;
    m.view.total_weight = hostile(rng);
    m.p_W = m.view.q;
    m.v_W = Vec3(hostile(rng), 0, 0) * 1e-4;
    m.q_WB = Eigen::Quaterniond(1, rng() % 4 == 0 ? hostile(rng) : 0.0, 0, 0);
    const std::size_t links = rng() % 4;
    for (std::size_t k = 0; k < links; ++k)
      m.links.emplace_back(static_cast<AgentId>(rng() % 5), hostile(rng));
    if (rng() % 2)
      m.view.flows.push_back(
          {static_cast<AgentId>(rng() % 5), Vec3(hostile(rng), 0, 0), hostile(rng), true});
    const std::string why = check_message(m);
    const SampleGate::Result r = gate.admit(m, why);
    if (r.verdict == SampleGate::Verdict::kAccepted) {
      ++admitted;
      // What is admitted is finite and bounded: it can reach a law without harm.
      ASSERT_TRUE(m.view.q.allFinite() && m.p_W.allFinite() && std::isfinite(m.stamp_s));
      ASSERT_TRUE(std::isfinite(m.view.total_weight) && m.view.total_weight >= 0.0);
      ASSERT_LE(m.view.q.cwiseAbs().maxCoeff(), 1e6);
      for (const auto& [peer, w] : m.links) ASSERT_TRUE(std::isfinite(w) && w >= 0.0);
      for (const FlowEntry& f : m.view.flows) ASSERT_TRUE(f.flow.allFinite());
      ASSERT_NE(m.view.id, 0u);
    } else {
      ++refused;
    }
  }
  EXPECT_GT(admitted, 0);
  EXPECT_GT(refused, n / 2);
  EXPECT_EQ(gate.counters().received, static_cast<std::uint64_t>(admitted));
}

}  // namespace
}  // namespace qswarm
