// Multi-process acceptance tests: real agent processes, each with its own DDS participant, plus
// the supervisor, launched by `swarm run` exactly as a user would. Each test has its own DDS domain
// so parallel ctest runs do not cross-talk.
#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <system_error>

#include "common/core/graph.hpp"
#include "common/core/law_registry.hpp"
#include "common/dds/dds_bus.hpp"
#include "common/mcap/file_check.hpp"
#include "common/scenario/scenario.hpp"
#include "tests/mcap/validate.hpp"
#include "tests/support/cannot_run.hpp"
#include "tests/swarm/domain_lease.hpp"
#include "tests/swarm/harness.hpp"

namespace qswarm::test {
namespace {

Vec3 vec(const google::protobuf::RepeatedField<double>& f) {
  return f.size() == 3 ? Vec3(f[0], f[1], f[2]) : Vec3::Constant(std::nan(""));
}

struct PaperCase {
  std::string scenario;
  Vec3 agreement;  // the paper's point
};
void PrintTo(const PaperCase& c, std::ostream* os) { *os << c.scenario; }

void expect_met_at(const records::Summary& s, const Vec3& point, double tol, bool physical) {
  ASSERT_EQ(s.agents_size(), 4);
  for (const auto& a : s.agents()) {
    const Vec3 q = vec(a.final_consensus());
    const Vec3 p = vec(a.final_position());
    EXPECT_LT((q - point).norm(), tol) << "agent " << a.id() << " consensus " << q.transpose();
    if (physical)
      EXPECT_LT((p - point).norm(), tol) << "agent " << a.id() << " position " << p.transpose();
  }
}

Result swarm_run(const std::string& scen, const std::filesystem::path& out, double time_scale,
                 std::vector<std::string> extra = {}) {
  std::vector<std::string> argv = {bin("swarm"),
                                   "run",
                                   scen,
                                   "--out",
                                   out.string(),
                                   "--domain",
                                   test_domain().str(),
                                   "--time-scale",
                                   std::to_string(time_scale),
                                   "--quiet"};
  argv.insert(argv.end(), extra.begin(), extra.end());
  return run(argv, 240.0);
}

class PaperParticle : public ::testing::TestWithParam<PaperCase> {};

TEST_P(PaperParticle, FourAgentProcessesMeetAtThePapersPointWithin1cm) {
  const PaperCase& c = GetParam();
  const auto dir = fresh_dir("particle-" + c.scenario);
  const Result r = swarm_run(scenario("paper/" + c.scenario), dir, 4.0);
  ASSERT_EQ(r.code, 0) << r.output;
  const records::Summary s = read_summary(dir);
  EXPECT_TRUE(s.converged());
  EXPECT_EQ(s.mode(), "particle");
  EXPECT_EQ(s.joins(), 4u);
  expect_met_at(s, c.agreement, 0.01, /*physical=*/true);
  EXPECT_LT(s.average_drift_m(), 1e-3);
  EXPECT_EQ(s.messages().dropped(), 0u);
  EXPECT_GT(s.messages().received(), 100u);
}

INSTANTIATE_TEST_SUITE_P(Paper, PaperParticle,
                         ::testing::Values(PaperCase{"unweighted", {10.25, 9.75, 29.25}},
                                           PaperCase{"weighted", {9, 12.75, 30.25}},
                                           PaperCase{"time_varying", {15.25, 10.25, 31}}),
                         [](const ::testing::TestParamInfo<PaperCase>& p) {
                           return "paper_" + p.param.scenario;
                         });

// A scenario file: `base` with `extra` appended (a field it does not set), next to the run.
std::string variant(const std::string& base, const std::string& extra,
                    const std::filesystem::path& dir) {
  std::ifstream in(base);
  std::stringstream text;
  text << in.rdbuf() << "\n" << extra << "\n";
  const std::filesystem::path out =
      dir.parent_path() / (dir.filename().string() + "-scenario.txtpb");
  std::ofstream(out) << text.str();
  return out.string();
}

class PaperQuadcopter : public ::testing::TestWithParam<PaperCase> {};

TEST_P(PaperQuadcopter, FourQuadcoptersAgreeOnThePapersPointAndClusterAboutItNeverCloserThan1m) {
  const PaperCase& c = GetParam();
  const auto dir = fresh_dir("quadcopter-" + c.scenario);
  const Result r = swarm_run(scenario("paper/" + c.scenario + "_quadcopter"), dir, 2.0);
  ASSERT_EQ(r.code, 0) << r.output;
  const records::Summary s = read_summary(dir);
  EXPECT_TRUE(s.converged());
  EXPECT_EQ(s.mode(), "quadcopter");
  // The agreement is the paper's; collision avoidance (on by default for quadcopters) keeps the
  // four off the one point: a cluster about it, every pair at least the safe distance apart, all
  // four held (their slots coincide), each held off by a neighbour at about the filter's 1.3 m.
  expect_met_at(s, c.agreement, 0.10, /*physical=*/false);
  EXPECT_TRUE(s.avoidance());
  EXPECT_EQ(s.safe_distance_m(), 1.0);
  EXPECT_GE(s.min_separation_m(), s.safe_distance_m());
  EXPECT_EQ(s.separation_violations(), 0u);
  EXPECT_EQ(s.held_agents_size(), 4);
  for (const auto& a : s.agents()) {
    double nearest = 1e300;
    for (const auto& b : s.agents())
      if (b.id() != a.id())
        nearest = std::min(nearest, (vec(a.final_position()) - vec(b.final_position())).norm());
    EXPECT_LT(nearest, 1.3 + 0.25) << "agent " << a.id() << " is not held by anyone";
    EXPECT_LT((vec(a.final_position()) - c.agreement).norm(), 3 * (1.3 + 0.25)) << a.id();
  }
  // The quadcopters really flew: the telemetry has rotor speeds near hover and moving positions.
  const auto rows = read_csv(dir / "telemetry.csv");
  ASSERT_FALSE(rows.empty());
  double max_rotor = 0.0;
  for (const auto& row : rows) max_rotor = std::max(max_rotor, std::stod(row.at("w1")));
  EXPECT_GT(max_rotor, 150.0);
  EXPECT_LE(max_rotor, 350.0);
}

INSTANTIATE_TEST_SUITE_P(Paper, PaperQuadcopter,
                         ::testing::Values(PaperCase{"unweighted", {10.25, 9.75, 29.25}},
                                           PaperCase{"weighted", {9, 12.75, 30.25}},
                                           PaperCase{"time_varying", {15.25, 10.25, 31}}),
                         [](const ::testing::TestParamInfo<PaperCase>& p) {
                           return "paper_" + p.param.scenario;
                         });

TEST(SwarmRun, WithAvoidanceOffFourQuadcoptersMeetOnThePointAndTheRecordCountsTheViolations) {
  // The paper's own comparison (point agents' paths flown by quadcopters): avoidance off by the
  // scenario switch, they meet within 10 cm of the point, and the record says they came closer
  // than the safe distance.
  const auto dir = fresh_dir("quadcopter-no-avoidance");
  const Result r = swarm_run(
      variant(scenario("paper/unweighted_quadcopter"), "avoidance { enabled: false }", dir), dir,
      2.0);
  ASSERT_EQ(r.code, 0) << r.output;
  const records::Summary s = read_summary(dir);
  EXPECT_TRUE(s.converged());
  EXPECT_FALSE(s.avoidance());
  expect_met_at(s, {10.25, 9.75, 29.25}, 0.10, /*physical=*/true);
  EXPECT_LT(s.min_separation_m(), 0.2);
  EXPECT_GE(s.separation_violations(), 3u);  // every pair that met (6 when all four did)
  EXPECT_EQ(s.held_agents_size(), 0);
  std::ifstream out(dir / "supervisor.out");  // the summary for people says so too
  std::stringstream text;
  text << out.rdbuf();
  EXPECT_NE(text.str().find("collision avoidance off: " +
                            std::to_string(s.separation_violations()) + " violations"),
            std::string::npos)
      << text.str();
}

TEST(SwarmRun, AUsersPlantFliesAgentProcessesBehindTheSameLawAndAvoidance) {
  // The plant written only through the plant seam, chosen over the scenario's quadcopters, in four
  // agent processes,
  const auto dir = fresh_dir("point-mass");
  const Result r = swarm_run(scenario("paper/unweighted_quadcopter"), dir, 2.0,
                             {"--plant", "double-integrator"});
  ASSERT_EQ(r.code, 0) << r.output;
  // agrees on the paper's point and keeps the safe distance about it, as the quadcopters do;
  const records::Summary s = read_summary(dir);
  EXPECT_TRUE(s.converged());
  EXPECT_EQ(s.mode(), "point-mass");
  expect_met_at(s, {10.25, 9.75, 29.25}, 0.10, /*physical=*/false);
  EXPECT_TRUE(s.avoidance());
  EXPECT_GE(s.min_separation_m(), s.safe_distance_m());
  EXPECT_EQ(s.separation_violations(), 0u);
  // its samples carry no attitude or rotors, and the scenario as run names it with its parameters.
  const auto rows = read_csv(dir / "telemetry.csv");
  ASSERT_FALSE(rows.empty());
  for (const auto& row : rows) {
    ASSERT_EQ(row.at("mode"), "0");
    ASSERT_EQ(std::stod(row.at("w1")), 0.0);
  }
  const std::string as_run = read_file(dir / "scenario.txtpb");
  EXPECT_NE(as_run.find("plant: \"point-mass\""), std::string::npos) << as_run;
  EXPECT_NE(as_run.find("key: \"max_accel_mps2\""), std::string::npos) << as_run;
}

TEST(SwarmRun, TwelveSeededRandomAgentsConvergeToTheirInitialAverage) {
  const auto dir = fresh_dir("random12");
  const Result r = run({bin("swarm"), "run", "--agents", "12", "--seed", "7", "--out", dir.string(),
                        "--domain", test_domain().str(), "--time-scale", "2", "--quiet"},
                       240.0);
  ASSERT_EQ(r.code, 0) << r.output;
  const records::Summary s = read_summary(dir);
  EXPECT_TRUE(s.converged());
  EXPECT_EQ(s.seed(), 7u);
  ASSERT_EQ(s.agents_size(), 12);
  // The positions are the seeded ones, independently regenerated here.
  const auto specs = random_agent_specs(12, 7, 30.0);
  Vec3 avg = Vec3::Zero();
  for (const auto& a : specs) avg += a.position_W / 12.0;
  EXPECT_LT((vec(s.initial_average()) - avg).norm(), 1e-9);
  for (int i = 0; i < 12; ++i) {
    EXPECT_LT((vec(s.agents(i).initial_position()) - specs[i].position_W).norm(), 1e-9);
    EXPECT_LT((vec(s.agents(i).final_consensus()) - avg).norm(), 0.02)
        << "agent " << s.agents(i).id();
  }
  EXPECT_LT(s.average_drift_m(), 1e-3);
}

// transport.receive TICK (each agent's tick reads its sockets, no receive threads) and THREADS
// (Fast DDS's): loss (the fault bus's, and the test transport's below the application), a kill
// and a restart, and a late joiner, and the swarm still meets at the exact initial average; at
// the tick every agent's sockets were read by its drains.
TEST(SwarmRun, AgentsReceivingAtTheTickOrOnThreadsKeepTheExactAverageThroughFaults) {
  for (const std::string receive : {"TICK", "THREADS"}) {
    const auto dir = fresh_dir("receive-" + receive);
    const auto scen = dir.parent_path() / ("receive-" + receive + ".txtpb");
    std::ofstream(scen) << read_file(scenario("faults_six")) << "transport { receive: " << receive
                        << " }\n"
                           "faults { loss { probability: 0.2 } transport_drop_percent: 10 "
                           "kill { agent: 2 at_s: 3 restart_at_s: 6 } "
                           "late_join { agent: 6 at_s: 2 } }\n";
    const Result r = run({bin("swarm"), "run", scen.string(), "--out", dir.string(), "--domain",
                          test_domain().str(), "--time-scale", "2", "--quiet"},
                         240.0);
    ASSERT_EQ(r.code, 0) << receive << ": " << r.output;
    const records::Summary s = read_summary(dir);
    EXPECT_TRUE(s.converged()) << receive << ": " << s.end_reason();
    EXPECT_EQ(s.faults().restarts(), 1u) << receive;
    EXPECT_EQ(s.faults().late_joins(), 1u) << receive;
    EXPECT_LT(s.average_relative_error(), 1e-9) << receive;
    EXPECT_NE(read_file(dir / "scenario.txtpb").find("receive: " + receive), std::string::npos);
    for (unsigned id = 1; id <= 6; ++id) {
      EXPECT_EQ(stats_value(dir, id, "tick_datagrams") > 0, receive == "TICK")
          << receive << ", agent " << id;
      EXPECT_LE(stats_value(dir, id, "tick_truncated"), 0) << receive << ", agent " << id;
    }
  }
}

// The most clients a run's Discovery Server knew at once: it prints its count when it changes
// (polled every 200 ms). -1 if it never printed one.
int most_clients(const std::filesystem::path& out) {
  const std::string served = read_file(out);
  int most = -1;
  for (std::size_t at = served.find("swarm-discovery: "); at != std::string::npos;
       at = served.find("swarm-discovery: ", at + 1)) {
    const char* count = served.c_str() + at + 17;
    if (std::isdigit(static_cast<unsigned char>(*count))) most = std::max(most, std::atoi(count));
  }
  return most;
}

// transport.discovery SERVER: the launcher starts the run's own two Discovery Servers first, on
// ports of the run's block, every participant discovers through them, and they stop with the run.
TEST(SwarmRun, ASwarmDiscoveringThroughItsOwnServerConvergesAndTheServerStopsWithIt) {
  const auto dir = fresh_dir("discovery-server");
  const auto scen = dir.parent_path() / "discovery-server.txtpb";
  // The six agents of the fault runs (complete graph), discovering through a server.
  std::ofstream(scen) << read_file(scenario("faults_six")) << "transport { discovery: SERVER }\n";
  const Result r = run({bin("swarm"), "run", scen.string(), "--out", dir.string(), "--domain",
                        test_domain().str(), "--time-scale", "2", "--quiet"},
                       240.0);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(read_summary(dir).converged());
  EXPECT_EQ(read_summary(dir).notes_size(), 0);
  for (unsigned k = 0; k < 2; ++k) {
    const pid_t server = pid_of(dir, "discovery", k);
    ASSERT_GT(server, 0) << read_file(dir / "processes.csv");
    EXPECT_FALSE(process_alive(server));
    // At its height each knew the six agents, the supervisor and the other server.
    EXPECT_EQ(most_clients(dir / ("discovery-" + std::to_string(k) + ".out")), 8) << k;
  }
  EXPECT_NE(read_file(dir / "scenario.txtpb").find("discovery: SERVER"), std::string::npos);
}

// A Discovery Server that hangs as Fast DDS 2.9.1's can (W5: it relays nothing more and ignores
// SIGTERM), here from the moment it listens, before anyone has met: the run's other server
// introduces everyone, the run converges, and its record and output name the hung one.
TEST(SwarmRun, ARunWhoseDiscoveryServerHangsMeetsThroughItsOtherAndSaysSo) {
  const auto dir = fresh_dir("hung-server");
  const auto scen = dir.parent_path() / "hung-server.txtpb";
  std::ofstream(scen) << read_file(scenario("faults_six")) << "transport { discovery: SERVER }\n";
  const Result r =
      run({bin("swarm"), "run", scen.string(), "--out", dir.string(), "--domain",
           test_domain().str(), "--time-scale", "2", "--quiet", "--test-hung-server", "0"},
          240.0);
  ASSERT_EQ(r.code, 0) << r.output;
  const records::Summary s = read_summary(dir);
  EXPECT_TRUE(s.converged());
  EXPECT_TRUE(s.missing_agents().empty());
  const std::string note =
      "Discovery Server 0 hung: it did not stop within 5 s of SIGTERM; Discovery Server 1 served "
      "to the end";
  ASSERT_EQ(s.notes_size(), 1);
  EXPECT_EQ(s.notes(0), note);
  EXPECT_NE(r.output.find(note), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("(1 needed SIGKILL)"), std::string::npos) << r.output;
  // Server 0 stopped as it listened, before anyone reached it. Server 1 knew the six agents and
  // the supervisor (and server 0, if its first announcement left before it stopped).
  EXPECT_NE(read_file(dir / "discovery-0.out").find("hanging (--test-hang)"), std::string::npos);
  const int known = most_clients(dir / "discovery-1.out");
  EXPECT_TRUE(known == 7 || known == 8) << read_file(dir / "discovery-1.out");
  for (unsigned k = 0; k < 2; ++k) EXPECT_FALSE(process_alive(pid_of(dir, "discovery", k)));
}

// Through the servers, an agent that hears its neighbours by name (a FIXED graph) is introduced to
// them, the supervisor and the two servers alone: on a 12-agent ring of degree 4 no agent ever
// knew more than those 7 participants (simple discovery: all 12 others).
TEST(SwarmRun, ThroughItsServerAnAgentOnAFixedGraphMeetsOnlyItsNeighbours) {
  const auto dir = fresh_dir("ring-server");
  const auto scen = dir.parent_path() / "ring-server.txtpb";
  {
    std::ofstream f(scen);
    f << "random_agents { count: 12 box_m: 10 }\nmode: PARTICLE\nlaw: EDGE_FLOW\n"
         "weight { policy: UNWEIGHTED }\n"
         "convergence { tolerance_m: 0.01 hold_s: 0.5 }\nduration_s: 60\nseed: 5\n"
         "transport { discovery: SERVER }\ntopology { policy: FIXED";
    for (int i = 1; i <= 12; ++i)
      f << " edges { a: " << i << " b: " << i % 12 + 1 << " } edges { a: " << i
        << " b: " << (i + 1) % 12 + 1 << " }";
    f << " }\n";
  }
  const Result r = run({bin("swarm"), "run", scen.string(), "--out", dir.string(), "--domain",
                        test_domain().str(), "--time-scale", "2", "--quiet"},
                       240.0);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(read_summary(dir).converged());
  for (unsigned id = 1; id <= 12; ++id) {
    const double known = stats_value(dir, id, "participants");
    EXPECT_GE(known, 0) << "agent " << id << " wrote no participant count";
    EXPECT_LE(known, 7) << "agent " << id;
  }
}

// scenarios/formation_grid16.txtpb: 16 quadcopter processes agree on a centre (the average of their
// estimates, position minus slot) and fly to a 4 x 4 grid, 3 m apart, about it, over 8 m radio
// links, with collision avoidance (on by default for quadcopters).
void expect_grid_formed(const std::filesystem::path& dir, const RunConfig& rc) {
  const records::Summary s = read_summary(dir);
  EXPECT_TRUE(s.converged());
  ASSERT_EQ(s.agents_size(), 16);
  EXPECT_LT((vec(s.initial_average()) - rc.initial_average()).norm(), 1e-9);
  EXPECT_LT(s.average_relative_error(), 1e-9);  // edge-flow: the centre is exact
  EXPECT_LT(s.max_slot_error_m(), 0.10);        // everyone within 10 cm of its slot
  for (const auto& a : s.agents()) {
    const AgentSpec* spec = rc.spec(a.id());
    ASSERT_NE(spec, nullptr);
    EXPECT_LT((vec(a.offset()) - spec->offset_W).norm(), 1e-12) << "agent " << a.id();
    EXPECT_LT(a.slot_error_m(), 0.10) << "agent " << a.id();
  }
  // Never closer than the safe distance, over every sample of the run; the closest pair is named.
  EXPECT_TRUE(s.avoidance());
  EXPECT_GE(s.min_separation_m(), s.safe_distance_m());
  EXPECT_EQ(s.separation_violations(), 0u);
  EXPECT_EQ(s.held_agents_size(), 0);  // 3 m slots: every one reachable
  ASSERT_EQ(s.min_separation_agents_size(), 2);
  EXPECT_NE(s.min_separation_agents(0), s.min_separation_agents(1));
  EXPECT_GE(s.min_separation_t_s(), 0.0);
  EXPECT_LE(s.min_separation_t_s(), s.duration_s());
}

TEST(SwarmRun, SixteenQuadcoptersFlyToTheirGridSlotsAboutTheExactCentreNeverCloserThan1m) {
  const auto dir = fresh_dir("formation16");
  const Result r = swarm_run(scenario("formation_grid16"), dir, 1.0);
  ASSERT_EQ(r.code, 0) << r.output;
  expect_grid_formed(dir, load_scenario(scenario("formation_grid16")));
}

TEST(SwarmRun, TheGridFormsApartUnder30PercentLossAndAKilledAndRestartedAgent) {
  const auto dir = fresh_dir("formation16-faults");
  const Result r =
      swarm_run(scenario("formation_grid16"), dir, 1.0, {"--loss", "0.3", "--kill", "9@2:4"});
  ASSERT_EQ(r.code, 0) << r.output;
  expect_grid_formed(dir, load_scenario(scenario("formation_grid16")));
  const records::Summary s = read_summary(dir);
  EXPECT_EQ(s.faults().kills(), 1u);
  EXPECT_EQ(s.faults().restarts(), 1u);
  EXPECT_GT(s.faults().injected().loss(), 1000u);
}

TEST(SwarmRun, TheSameGridWithAvoidanceOffComesCloserThanTheSafeDistance) {
  // So the separation metric can fail: the same seed and slots, the filter switched off (the starts
  // are then the plain uniform draw, which does not keep them the safe distance apart).
  const auto dir = fresh_dir("formation16-off");
  const Result r = swarm_run(
      variant(scenario("formation_grid16"), "avoidance { enabled: false }", dir), dir, 1.0);
  ASSERT_EQ(r.code, 0) << r.output;
  const records::Summary s = read_summary(dir);
  EXPECT_TRUE(s.converged());
  EXPECT_FALSE(s.avoidance());
  EXPECT_LT(s.min_separation_m(), s.safe_distance_m());
  EXPECT_GT(s.separation_violations(), 0u);
}

TEST(SwarmRun, SixtyFourAgentsFormALatticeOverRadioRangeAndTheGraphStaysSparse) {
  // scenarios/formation_lattice64.txtpb: 64 agent processes, links only within 4.5 m.
  const auto dir = fresh_dir("lattice64");
  // Half real time: 64 processes need about 1.5 of the 2 cores at full speed on a good day, and
  // these shared machines run at half speed on a bad one (RK4 step 463 ns one day, 1.2 us another);
  // overloaded, the supervisor misses most samples and takes live agents for departed ones.
  const Result r = swarm_run(scenario("formation_lattice64"), dir, 0.5);
  ASSERT_EQ(r.code, 0) << r.output;
  const records::Summary s = read_summary(dir);
  EXPECT_TRUE(s.converged());
  ASSERT_EQ(s.agents_size(), 64);
  EXPECT_LT(s.max_slot_error_m(), 0.01);
  // The centre: edge-flow keeps the sum exact; what is left is the flows in flight between the
  // last samples the (busy) supervisor holds of 64 agents, a tick or more apart (measured 2e-6 to
  // 4e-6 of |centre|).
  EXPECT_LT(s.average_relative_error(), 1e-4);
  // Sparse: degrees at the end, against the 63 of a complete graph.
  std::map<std::uint32_t, int> degree;
  for (const auto& e : s.edges_final()) {
    ++degree[static_cast<std::uint32_t>(e.values(0).number_value())];
    ++degree[static_cast<std::uint32_t>(e.values(1).number_value())];
  }
  ASSERT_EQ(degree.size(), 64u);  // nobody isolated
  int largest = 0;
  for (const auto& [id, d] : degree) largest = std::max(largest, d);
  const double mean = 2.0 * s.edges_final_size() / 64.0;
  std::printf("64-agent lattice: mean degree %.2f, largest %d (complete graph: 63), lambda2 %.3f\n",
              mean, largest, s.lambda2_final());
  EXPECT_LE(largest, 18);  // a lattice slot has at most 18 others within 4.5 m
  EXPECT_LT(mean, 16.0);
  EXPECT_GT(s.lambda2_final(), 0.0);  // connected
}

TEST(SwarmRun, ProximityAddsLinksAtRuntimeVisibleInGraphCsv) {
  const auto dir = fresh_dir("proximity");
  const Result r = swarm_run(scenario("paper/time_varying"), dir, 4.0);
  ASSERT_EQ(r.code, 0) << r.output;
  const auto rows = read_csv(dir / "graph.csv");
  int first_full_edges = -1, last_edges = -1;
  double first_added_t = -1.0;
  for (const auto& row : rows) {
    if (std::stoi(row.at("agents")) != 4) continue;
    const int e = std::stoi(row.at("edges"));
    if (first_full_edges < 0) first_full_edges = e;
    if (first_added_t < 0 && e > first_full_edges) first_added_t = std::stod(row.at("t_s"));
    last_edges = e;
  }
  EXPECT_EQ(first_full_edges, 3);  // sparse and connected: the paper's 1-3, 1-4, 2-3
  EXPECT_EQ(last_edges, 6);        // complete at the end
  EXPECT_GT(first_added_t, 0.0);
  const records::Summary s = read_summary(dir);
  EXPECT_EQ(s.edges_initial_size(), 3);
  EXPECT_EQ(s.edges_final_size(), 6);
  EXPECT_NEAR(s.lambda2_initial(), 6.2395, 5e-3);  // the paper's L_2i
}

TEST(SwarmRun, SigkillOfOneAgentIsRecordedAndTheOthersAgree) {
  const auto dir = fresh_dir("sigkill");
  Child launcher({bin("swarm"), "run", "--agents", "12", "--seed", "7", "--out", dir.string(),
                  "--domain", test_domain().str(), "--time-scale", "1", "--quiet"},
                 dir.parent_path() / "sigkill.log");
  // Wait until the swarm is running (the supervisor has graph rows with all 12 agents).
  ASSERT_TRUE(wait_for(
      [&] {
        for (const auto& row : read_csv(dir / "graph.csv"))
          if (std::stoi(row.at("agents")) == 12 && std::stod(row.at("t_s")) > 0.5) return true;
        return false;
      },
      60.0));
  const pid_t victim = pid_of(dir, "agent", 5);
  ASSERT_GT(victim, 0);
  ASSERT_EQ(::kill(victim, SIGKILL), 0);
  const Result r = launcher.wait(240.0);
  // The others agree, but a run that lost an agent has not converged: exit 1, and the record
  // says who was missing.
  ASSERT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("agent 5 killed by signal"), std::string::npos) << r.output;
  bool departed = false;
  for (const auto& row : read_csv(dir / "events.csv"))
    if (row.at("kind") == "depart" && row.at("agent") == "5") departed = true;
  EXPECT_TRUE(departed);
  const records::Summary s = read_summary(dir);
  EXPECT_FALSE(s.converged());
  // The supervisor's verdict, then what the launcher saw: agent 5's death by a signal.
  EXPECT_EQ(s.end_reason().rfind("agreed without agent 5; agent 5 killed by signal", 0), 0u)
      << s.end_reason();
  ASSERT_EQ(s.missing_agents_size(), 1);
  EXPECT_EQ(s.missing_agents(0), 5u);
  EXPECT_GE(s.departures(), 1u);
  // The eleven survivors agree.
  Positions q;
  for (const auto& a : s.agents())
    if (a.id() != 5) q.push_back(vec(a.final_consensus()));
  EXPECT_LT(disagreement(q), 0.01);
}

TEST(SwarmRun, MalformedScenariosExit2NamingTheProblem) {
  const auto dir = fresh_dir("malformed");
  std::filesystem::create_directories(dir);
  const std::string agents =
      "agents { id: 1 position { x: 0 y: 0 z: 0 } }\nagents { id: 2 position { x: 1 y: 0 z: 0 } "
      "}\n";
  struct Case {
    std::string text, expect;
  };
  // Every field's check is a pure function tested in tests/runtime/scenario_test.cpp; here a few
  // cases prove the processes turn them into exit 2 with the message.
  const std::vector<Case> cases = {
      {"name: \"x\"\nagnets { id: 1 }\n", ".txtpb:2:"},                   // syntax: line
      {agents + "agents { id: 2 position { x: 5 } }\n", "agents[2].id"},  // duplicate
      {agents + "rates { physics_hz: 500 consensus_hz: 30 }\n", "rates.consensus_hz"},
      {agents + "faults { cut { a: 1 b: 7 start_s: 1 end_s: 2 } }\n", "faults.cut[0].b"},
  };
  int k = 0;
  for (const Case& c : cases) {
    const auto file = dir / ("bad" + std::to_string(k++) + ".txtpb");
    std::ofstream(file) << c.text;
    const Result r =
        run({bin("swarm"), "run", file.string(), "--out", (dir / "never").string(), "--quiet"});
    EXPECT_EQ(r.code, 2) << c.text << "\n" << r.output;
    EXPECT_NE(r.output.find(c.expect), std::string::npos)
        << "expected '" << c.expect << "' in: " << r.output;
    const Result ri = run({bin("swarm"), "inspect", file.string()});
    EXPECT_EQ(ri.code, 2) << ri.output;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "never" / "summary.json"));
  // Bad flags.
  EXPECT_EQ(run({bin("swarm"), "run", scenario("demo"), "--time-scale", "-1"}).code, 2);
  // Non-finite and out-of-range numbers are refused naming the flag (NaN passed CLI11's ranges).
  for (const auto& [flag, value] :
       std::vector<std::pair<std::string, std::string>>{{"--time-scale", "nan"},
                                                        {"--duration", "nan"},
                                                        {"--duration", "inf"},
                                                        {"--loss", "-0.5"},
                                                        {"--grace", "nan"},
                                                        {"--time-scale", "1e9"}}) {
    const Result bad = run({bin("swarm"), "run", scenario("demo"), flag, value, "--quiet"});
    EXPECT_EQ(bad.code, 2) << flag << " " << value << ": " << bad.output;
    EXPECT_NE(bad.output.find(flag + ":"), std::string::npos) << bad.output;
  }
  const Result agent_nan =
      run({bin("swarm-agent"), "--scenario", scenario("demo"), "--id", "1", "--time-scale", "nan"});
  EXPECT_EQ(agent_nan.code, 2) << agent_nan.output;
  EXPECT_EQ(run({bin("swarm"), "run", "--agents", "0"}).code, 2);
  const Result none = run({bin("swarm"), "run"});
  EXPECT_EQ(none.code, 2);
  EXPECT_NE(none.output.find("--agents"), std::string::npos) << none.output;
  EXPECT_EQ(run({bin("swarm"), "run", "/nonexistent.txtpb"}).code, 2);
  const Result bad_cut = run({bin("swarm"), "run", scenario("demo"), "--cut", "1to2@5:15"});
  EXPECT_EQ(bad_cut.code, 2);
  EXPECT_NE(bad_cut.output.find("--cut '1to2@5:15': expected A-B@START:END"), std::string::npos)
      << bad_cut.output;
  // An interface address this machine does not hold (TEST-NET-3) is refused before anything flies:
  // a participant bound to it hears nobody, and the agent would fly alone after its start timeout.
  for (const std::string prog : {"swarm-agent", "swarm-supervisor"}) {
    std::vector<std::string> argv = {bin(prog),    "--scenario",  scenario("demo"), "--run-dir",
                                     dir.string(), "--interface", "203.0.113.77"};
    if (prog == "swarm-agent") argv.insert(argv.end(), {"--id", "1"});
    const Result away = run(argv);
    EXPECT_EQ(away.code, 2) << prog << ": " << away.output;
    EXPECT_NE(away.output.find("--interface: expected \"any\" or an IPv4 address of this machine"),
              std::string::npos)
        << away.output;
  }
  const auto away_file = dir / "away.txtpb";
  std::ofstream(away_file) << agents << "transport { interface: \"203.0.113.77\" }\n";
  const Result away_run =
      run({bin("swarm"), "run", away_file.string(), "--out", (dir / "away").string(), "--quiet"});
  EXPECT_EQ(away_run.code, 2) << away_run.output;
  EXPECT_NE(away_run.output.find("transport.interface"), std::string::npos) << away_run.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "away"));
  EXPECT_EQ(run({bin("swarm"), "run", scenario("demo"), "--loss", "2"}).code, 2);
  EXPECT_EQ(run({bin("swarm"), "run", scenario("demo"), "--law", "gossip"}).code, 2);
  const Result wrong_id = run({bin("swarm-agent"), "--scenario", scenario("demo"), "--id", "77"});
  EXPECT_EQ(wrong_id.code, 2);
  EXPECT_NE(wrong_id.output.find("--id"), std::string::npos) << wrong_id.output;
  // --peer-hosts: names or addresses, no port, and not beside a Discovery Server.
  for (const std::string hosts : {"agent supervisor", "10.0.0.1:7410", "agent,,supervisor", "-x"}) {
    const Result bad = run(
        {bin("swarm-agent"), "--scenario", scenario("demo"), "--id", "1", "--peer-hosts", hosts});
    EXPECT_EQ(bad.code, 2) << hosts << ": " << bad.output;
    EXPECT_NE(bad.output.find("--peer-hosts"), std::string::npos) << bad.output;
  }
  const Result both =
      run({bin("swarm-supervisor"), "--scenario", scenario("demo"), "--run-dir", dir.string(),
           "--peer-hosts", "agent", "--discovery-server", "127.0.0.1:11811"});
  EXPECT_EQ(both.code, 2) << both.output;
  EXPECT_NE(both.output.find("--peer-hosts (QSWARM_PEER_HOSTS) and --discovery-server"),
            std::string::npos)
      << both.output;
}

// `swarm run` of the paper's unweighted scenario (with `extra` flags) into `dir` beside a saboteur
// inside the run: a participant on its partition, which knows the run's id from the record.
// `round(saboteur, run_id)` publishes every 50 ms while the run flies. Returns the launcher's
// result and the rounds published.
std::pair<Result, int> fly_beside_saboteur(
    const std::filesystem::path& dir, const std::vector<std::string>& extra,
    const std::function<void(DdsBus&, std::uint64_t)>& round) {
  std::vector<std::string> argv = {
      bin("swarm"), "run",      scenario("paper/unweighted"), "--out",
      dir.string(), "--domain", test_domain().str(),          "--time-scale",
      "1",          "--quiet"};
  argv.insert(argv.end(), extra.begin(), extra.end());
  Child launcher(argv, dir.parent_path() / (dir.filename().string() + ".log"));
  EXPECT_TRUE(wait_for([&] { return std::filesystem::exists(dir / "processes.csv"); }, 30.0));
  const std::uint64_t run_id = load_scenario((dir / "scenario.txtpb").string()).transport.run_id;
  EXPECT_NE(run_id, 0u);
  DdsOptions opt;
  opt.participant.domain_id = static_cast<std::uint32_t>(test_domain().domain());
  opt.participant.name = "test-saboteur";
  opt.state.run_id = run_id;
  DdsBus saboteur(opt);
  int rounds = 0;
  while (launcher.running()) {
    round(saboteur, run_id);
    ++rounds;
    wait_for([&] { return !launcher.running(); }, 0.05);
  }
  return {launcher.wait(10.0), rounds};
}

TEST(SwarmRun, BadSamplesFromATestParticipantAreDroppedByEveryAgentAndChangeNothing) {
  const auto dir = fresh_dir("bad-samples");
  // It publishes where the agents listen: a swarm of four hears the whole run's partition.
  std::uint64_t seq = 1u << 30;
  std::int64_t life =
      system_clock().wall_ns() + 1'000'000'000'000LL;  // "newer" than any agent's incarnation
  const auto [r, published] =
      fly_beside_saboteur(dir, {}, [&](DdsBus& saboteur, std::uint64_t run_id) {
        StateMessage nan_msg;  // a stranger with NaN consensus
        nan_msg.view.id = 99;
        nan_msg.view.q = Vec3(std::nan(""), 0, 0);
        nan_msg.phase = Phase::kRunning;
        nan_msg.seq = ++seq;
        nan_msg.incarnation = life;
        nan_msg.run_id = run_id;
        saboteur.publish(nan_msg);
        StateMessage absurd;  // impersonates agent 2 with an absurd position and flow
        absurd.view.id = 2;
        absurd.view.q = Vec3(1e12, 0, 0);
        absurd.view.flows.push_back({3, Vec3(0, 1e300 * 10, 0), 1.0, true});
        absurd.phase = Phase::kRunning;
        absurd.seq = ++seq;
        absurd.incarnation = life;
        absurd.run_id = run_id;
        saboteur.publish(absurd);
        StateMessage stranger;  // well-formed, but not an agent of the scenario
        stranger.view.id = 77;
        stranger.view.q = Vec3(100, 100, 100);
        stranger.p_W = stranger.view.q;
        stranger.phase = Phase::kRunning;
        stranger.seq = ++seq;
        stranger.incarnation =
            system_clock().wall_ns();  // plausible: a far-future one is refused as such
        stranger.run_id = run_id;
        saboteur.publish(stranger);
      });
  ASSERT_EQ(r.code, 0) << r.output;
  ASSERT_GT(published, 10);
  const records::Summary s = read_summary(dir);
  EXPECT_TRUE(s.converged());
  // Each saboteur round sends three samples every agent's gate drops and counts (NaN, a future
  // incarnation, an agent not in the scenario); agent 2 takes the one with its own id for its own
  // echo. A best-effort sample may be lost and the last ones come after an agent's stats, so the
  // count lies between one and that per round; more is a sample counted twice.
  for (const auto& a : s.agents()) {
    const double per_round = a.id() == 2 ? 2.0 : 3.0;
    const double dropped = stats_value(dir, a.id(), "dropped");
    EXPECT_GE(dropped, 1) << "agent " << a.id();
    EXPECT_LE(dropped, per_round * published) << "agent " << a.id();
    EXPECT_GE(a.dropped_by_agent(), 1u) << "agent " << a.id() << ": the summary counts them";
  }
  // The stranger is noted once and kept out of the swarm's record.
  EXPECT_EQ(s.agents_size(), 4);
  int noted = 0;
  for (const auto& row : read_csv(dir / "events.csv"))
    noted += (row.at("kind") == "unknown_agent" && row.at("agent") == "77") ? 1 : 0;
  EXPECT_EQ(noted, 1);
  expect_met_at(s, Vec3(10.25, 9.75, 29.25), 0.01, true);
  EXPECT_LT(s.average_drift_m(), 1e-3);
}

TEST(SwarmRun, AUsersLawFliesAgentProcessesAndSamplesNotOfItNeverReachIt) {
  // The example law written only through the law seam, by name, in four agent processes,
  const auto dir = fresh_dir("metropolis");
  // while an insider of the run sends samples of agents 2, 3 and 4 that are well formed but for
  // another law, or carry a longer payload than metropolis's, or a NaN in it
  std::uint64_t seq = 1u << 30;
  const auto [r, published] = fly_beside_saboteur(
      dir, {"--law", "metropolis"}, [&](DdsBus& saboteur, std::uint64_t run_id) {
        for (const AgentId id : {2u, 3u, 4u}) {
          StateMessage m;
          m.view.id = id;
          m.view.q = Vec3(500, 500, 500);
          m.view.law = law_tag(id == 2 ? "edge-flow" : "metropolis");
          m.view.payload = id == 3 ? std::vector<double>{1.0, 1.0} : std::vector<double>{1.0};
          if (id == 4) m.view.payload = {std::nan("")};
          m.phase = Phase::kRunning;
          m.seq = ++seq;
          m.incarnation = system_clock().wall_ns();
          m.run_id = run_id;
          saboteur.publish(m);
        }
      });
  ASSERT_EQ(r.code, 0) << r.output;
  ASSERT_GT(published, 5);
  // then the swarm agreed, the record says which law flew, and agent 1 named each refusal once
  const records::Summary s = read_summary(dir);
  EXPECT_TRUE(s.converged());
  EXPECT_EQ(s.law(), "metropolis");
  // A convex combination every tick: the agreed point lies inside the starts' box. It is not the
  // average (10.25, 9.75, 29.25): over DDS a neighbour's value is a tick old, and the two ends of
  // an edge then move by different amounts (`swarm check-law metropolis` measures it).
  const Positions starts = {{4, 17, 24}, {18, 10, 32}, {15, 10, 26}, {4, 2, 35}};
  for (const auto& a : s.agents()) {
    EXPECT_LT(outside_box_m({vec(a.final_consensus())}, starts), 1e-9) << a.id();
    if (a.id() == 1) EXPECT_GE(a.dropped_by_agent(), 3u);
  }
  const std::string log = read_file(dir / "agent-1.log");
  for (const char* why : {"from agent 2: a sample of another law",
                          "from agent 3: law payload longer than the law's bound",
                          "from agent 4: law payload not finite or absurd"}) {
    EXPECT_NE(log.find(why), std::string::npos) << why << " not in:\n" << log;
  }
}

// `swarm run` of the paper's time-varying rendezvous into `dir`, interrupted with SIGINT (Ctrl-C)
// once its 4 agents fly: what it said, and the pids of its agents and supervisor.
struct Interrupted {
  Result result;
  std::vector<pid_t> pids;
};
Interrupted interrupt_once_flying(const std::filesystem::path& dir,
                                  const std::vector<std::string>& extra) {
  std::vector<std::string> argv = {bin("swarm"),
                                   "run",
                                   scenario("paper/time_varying"),
                                   "--out",
                                   dir.string(),
                                   "--domain",
                                   test_domain().str(),
                                   "--time-scale",
                                   "0.5"};
  argv.insert(argv.end(), extra.begin(), extra.end());
  Child launcher(argv, dir.parent_path() / (dir.filename().string() + ".log"));
  Interrupted out;
  const bool flying = wait_for(
      [&] {
        for (const auto& row : read_csv(dir / "graph.csv"))
          if (std::stoi(row.at("agents")) == 4) return true;
        return false;
      },
      60.0);
  EXPECT_TRUE(flying) << "the 4 agents never flew";
  for (unsigned id = 1; id <= 4 && flying; ++id) out.pids.push_back(pid_of(dir, "agent", id));
  if (flying) out.pids.push_back(pid_of(dir, "supervisor", 0));
  for (pid_t p : out.pids) EXPECT_TRUE(process_alive(p)) << p;
  launcher.signal(SIGINT);
  out.result = launcher.wait(60.0);
  return out;
}

TEST(SwarmRun, CtrlCLeavesNoOrphansAndARecordThatSaysWhatIsMissing) {
  const auto dir = fresh_dir("ctrl-c");
  // Agent 2 ignores SIGTERM, so the launcher's escalation to SIGKILL is exercised too.
  const Interrupted run =
      interrupt_once_flying(dir, {"--grace", "1", "--test-ignore-sigterm", "2"});
  const Result& r = run.result;
  const std::vector<pid_t>& pids = run.pids;
  // Agent 2 could not write its stats (SIGKILL): the record is incomplete, and says which file.
  EXPECT_EQ(r.code, 3) << r.output;
  EXPECT_NE(r.output.find("1 needed SIGKILL"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("agent 2 wrote no agent-2.stats"), std::string::npos) << r.output;
  for (pid_t p : pids) EXPECT_FALSE(process_alive(p)) << "orphan pid " << p;
  const records::Summary s = read_summary(dir);
  // The supervisor's reason, then what only the launcher saw.
  EXPECT_EQ(s.end_reason(),
            "interrupted; record incomplete: agent 2 wrote no agent-2.stats (stopped at teardown "
            "after 1.000000 s of grace?)");
  EXPECT_FALSE(s.converged());
  EXPECT_EQ(s.agents_size(), 4);
  bool ended = false;
  for (const auto& row : read_csv(dir / "events.csv")) ended |= row.at("kind") == "end";
  EXPECT_TRUE(ended);
  EXPECT_GT(read_csv(dir / "telemetry.csv").size(), 10u);
  // The supervisor ended run.mcap on SIGTERM: footer, summary, every record of records.pb.
  const mcap::FileCheck c = mcap::check_file(dir / "run.mcap");
  EXPECT_TRUE(c.complete) << c.problem;
  QSWARM_REQUIRE_MCAP_VALIDATOR();
  const McapValidation v = validate_mcap(dir / "run.mcap", dir / "records.pb");
  EXPECT_EQ(v.code, 0) << v.output;
}

// The promise as users meet it: Ctrl-C of a run whose processes all stop when told. Every process
// is gone, the record is complete and says "interrupted", and the exit code is 1, never 0.
TEST(SwarmRun, CtrlCOfARunThatStopsWhenToldExitsOneWithACompleteRecordSayingInterrupted) {
  const auto dir = fresh_dir("ctrl-c-clean");
  const Interrupted run = interrupt_once_flying(dir, {});
  const Result& r = run.result;
  const std::vector<pid_t>& pids = run.pids;
  ASSERT_EQ(pids.size(), 5u);
  EXPECT_EQ(r.code, 1) << r.output;
  for (pid_t p : pids) EXPECT_FALSE(process_alive(p)) << "orphan pid " << p;
  const records::Summary s = read_summary(dir);
  EXPECT_EQ(s.end_reason(), "interrupted");
  EXPECT_FALSE(s.converged());
  EXPECT_EQ(s.agents_size(), 4);
  EXPECT_EQ(r.output.find("record incomplete"), std::string::npos) << r.output;
  for (unsigned id = 1; id <= 4; ++id)
    EXPECT_TRUE(std::filesystem::exists(dir / ("agent-" + std::to_string(id) + ".stats"))) << id;
  const mcap::FileCheck c = mcap::check_file(dir / "run.mcap");
  EXPECT_TRUE(c.complete) << c.problem;
}

// The launcher SIGKILLed while an agent is stopped (SIGSTOP): the agent's SIGTERM stays pending
// while it is stopped, so without the kernel's orphaned-group SIGCONT it would stay stopped for
// good.
TEST(SwarmRun, AnAgentStoppedWhenTheLauncherIsKilledStillStopsCleanlyAndLeavesNoOrphan) {
  const auto dir = fresh_dir("stopped-agent");
  Child launcher({bin("swarm"), "run", scenario("faults_six"), "--out", dir.string(), "--domain",
                  test_domain().str(), "--duration", "600", "--quiet"},
                 dir.parent_path() / "stopped-agent.log");
  // Once every agent flies (so each has its signal handlers and a stats file to write).
  ASSERT_TRUE(wait_for(
      [&] {
        for (const auto& row : read_csv(dir / "graph.csv"))
          if (std::stoi(row.at("agents")) == 6) return true;
        return false;
      },
      60.0));
  std::vector<pid_t> pids = {pid_of(dir, "supervisor", 0)};
  for (unsigned id = 1; id <= 6; ++id) pids.push_back(pid_of(dir, "agent", id));
  const pid_t stopped = pid_of(dir, "agent", 2);
  ASSERT_EQ(::kill(stopped, SIGSTOP), 0);
  // Stopped means every thread stopped: the kernel sends an orphaned group SIGHUP and SIGCONT only
  // if its stop is complete when the launcher dies, and a thread at nice 15 on a busy host can
  // take its time to stop after the main thread shows T (then the agent stayed stopped forever).
  ASSERT_TRUE(wait_for(
      [&] {
        const std::string proc = "/proc/" + std::to_string(stopped) + "/task";
        std::error_code ec;
        int threads = 0;
        for (auto t = std::filesystem::directory_iterator(proc, ec);
             !ec && t != std::filesystem::directory_iterator(); t.increment(ec)) {
          if (read_file(t->path() / "stat").find(") T ") == std::string::npos) return false;
          ++threads;
        }
        return !ec && threads > 0;
      },
      10.0));
  launcher.signal(SIGKILL);
  launcher.wait(10.0);
  // Every child, the stopped one included, is gone, and the stopped agent stopped cleanly.
  EXPECT_TRUE(wait_for(
      [&] {
        for (const pid_t p : pids)
          if (process_alive(p)) return false;
        return true;
      },
      30.0));
  for (std::size_t k = 0; k < pids.size(); ++k) {
    const pid_t p = pids[k];
    if (!process_alive(p)) continue;
    // What a survivor was doing, for a failure that is rare: its state, where it waits, its
    // threads, and the end of its log (k 0: the supervisor, k: agent k).
    const std::string proc = "/proc/" + std::to_string(p);
    std::string tasks;
    std::error_code ec;
    // Never throws: the survivor may exit while its threads are listed.
    for (auto t = std::filesystem::directory_iterator(proc + "/task", ec);
         !ec && t != std::filesystem::directory_iterator(); t.increment(ec))
      tasks += read_file(t->path() / "stat").substr(0, 60) + " wchan " +
               read_file(t->path() / "wchan") + "\n";
    const std::string log = read_file(
        dir / (k == 0 ? std::string("supervisor.log") : "agent-" + std::to_string(k) + ".log"));
    ADD_FAILURE() << "orphan pid " << p << " (" << (k == 0 ? "supervisor" : "agent")
                  << (k == 0 ? "" : " " + std::to_string(k)) << ")\n"
                  << tasks << "its log ends:\n"
                  << log.substr(log.size() > 1500 ? log.size() - 1500 : 0);
    ::kill(p, SIGKILL);
  }
  EXPECT_TRUE(std::filesystem::exists(dir / "agent-2.stats"));
}

TEST(Smoke, EveryBinaryRunsWithATinyDuration) {
  for (const std::string b : {"swarm", "swarm-agent", "swarm-supervisor", "swarm-preview"}) {
    const Result r = run({bin(b), "--help"});
    EXPECT_EQ(r.code, 0) << b << ": " << r.output;
  }
  const auto dir = fresh_dir("smoke");
  const Result r = swarm_run(scenario("demo"), dir, 1.0, {"--duration", "0.1"});
  EXPECT_EQ(r.code, 1) << r.output;  // 0.1 s is too short to converge: exit 1, record written
  const records::Summary s = read_summary(dir);
  EXPECT_EQ(s.end_reason(), "duration");
  EXPECT_TRUE(std::filesystem::exists(dir / "records.pb"));
  EXPECT_TRUE(std::filesystem::exists(dir / "scenario.txtpb"));
}

TEST(Smoke, InspectPredictsWithoutFlying) {
  const Result r = run({bin("swarm"), "inspect", scenario("paper/time_varying"), "--json"});
  ASSERT_EQ(r.code, 0) << r.output;
  records::Inspection ins;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(r.output, &ins).ok()) << r.output;
  EXPECT_EQ(ins.scenario(), "paper_time_varying");
  EXPECT_NEAR(ins.lambda2(), 6.2395, 5e-5);  // the printed matrix's lambda2 (the paper: 6.234)
  ASSERT_EQ(ins.agreement_point_size(), 3);
  EXPECT_DOUBLE_EQ(ins.agreement_point(0), 15.25);
  EXPECT_DOUBLE_EQ(ins.agreement_point(1), 10.25);
  EXPECT_DOUBLE_EQ(ins.agreement_point(2), 31.0);
  EXPECT_EQ(ins.edges_size(), 3);
  EXPECT_EQ(ins.laplacian_size(), 4);
  EXPECT_TRUE(ins.connected());
  EXPECT_FALSE(ins.avoidance());  // point agents
  const Result text = run({bin("swarm"), "inspect", scenario("paper/weighted")});
  EXPECT_NE(text.output.find("13.06"), std::string::npos) << text.output;
  // Quadcopters to one point: avoidance on, and every one of them held in a cluster.
  const Result quad =
      run({bin("swarm"), "inspect", scenario("paper/weighted_quadcopter"), "--json"});
  records::Inspection q;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(quad.output, &q).ok()) << quad.output;
  EXPECT_TRUE(q.avoidance());
  EXPECT_EQ(q.safe_distance_m(), 1.0);
  EXPECT_EQ(q.held_agents_size(), 4);
}

TEST(Record, ASecondRunOnTheSameOutIsRefusedAndADeadSupervisorStillLeavesASummary) {
  const auto dir = fresh_dir("dead-supervisor");
  Child launcher({bin("swarm"), "run", scenario("paper/time_varying"), "--out", dir.string(),
                  "--domain", test_domain().str(), "--time-scale", "1", "--quiet"},
                 dir.parent_path() / "dead-supervisor.log");
  ASSERT_TRUE(wait_for([&] { return pid_of(dir, "supervisor", 0) > 0; }, 30.0));
  // Given a run writing to dir, a second run given the same --out is refused.
  const Result second = run({bin("swarm"), "run", scenario("demo"), "--out", dir.string(),
                             "--domain", test_domain().str(), "--quiet"});
  EXPECT_EQ(second.code, 2) << second.output;
  EXPECT_NE(second.output.find("--out"), std::string::npos) << second.output;
  // When the supervisor dies mid-run, once run.mcap holds a chunk beyond its header and schemas
  ASSERT_TRUE(wait_for([&] { return std::filesystem::exists(dir / "supervisor.ready"); }, 60.0));
  const auto size = [&] {
    std::error_code ec;
    const auto n = std::filesystem::file_size(dir / "run.mcap", ec);
    return ec ? 0 : n;
  };
  const auto headed = size();
  ASSERT_TRUE(wait_for([&] { return size() > headed + 1000; }, 60.0));
  ASSERT_EQ(::kill(pid_of(dir, "supervisor", 0), SIGKILL), 0);
  const Result r = launcher.wait(60.0);
  // then the run fails, and the launcher's summary says why, run.mcap cut short among it.
  EXPECT_EQ(r.code, 1) << r.output;
  const records::Summary s = read_summary(dir);
  EXPECT_FALSE(s.converged());
  EXPECT_NE(s.end_reason().find("supervisor killed by signal"), std::string::npos)
      << s.end_reason();
  EXPECT_NE(s.end_reason().find("record incomplete: run.mcap: no footer"), std::string::npos)
      << s.end_reason();
  // Foxglove's indexed reader refuses the file; its streamed reader recovers a prefix of
  // records.pb.
  QSWARM_REQUIRE_MCAP_VALIDATOR();
  const McapValidation cut = validate_mcap(dir / "run.mcap", dir / "records.pb", true);
  EXPECT_EQ(cut.code, 0) << cut.output;
  // swarm export rebuilds it from records.pb (exit 2 if the kill cut records.pb mid-record too:
  // then its whole records), and says what it replaced.
  const Result e = run({bin("swarm"), "export", "--mcap", dir.string()});
  EXPECT_TRUE(e.code == 0 || (e.code == 2 && e.output.find("records.pb: cut inside a record") !=
                                                 std::string::npos))
      << e.output;
  EXPECT_NE(e.output.find("run.mcap was incomplete (no footer"), std::string::npos) << e.output;
  EXPECT_TRUE(mcap::check_file(dir / "run.mcap").complete);
  const McapValidation whole = validate_mcap(dir / "run.mcap", dir / "records.pb");
  EXPECT_EQ(whole.code, 0) << whole.output;
}

// A multi-process run's run.mcap opens in Foxglove's reader with every record of records.pb and a
// scene per snapshot; `swarm export` rebuilds the same bytes from records.pb.
TEST(Record, ASwarmRunsRunMcapOpensInFoxglovesReaderAndExportRebuildsItByteForByte) {
  QSWARM_REQUIRE_MCAP_VALIDATOR();
  const auto dir = fresh_dir("mcap");
  const Result r = swarm_run(scenario("demo"), dir, 2.0);
  ASSERT_EQ(r.code, 0) << r.output;
  const McapValidation v = validate_mcap(dir / "run.mcap", dir / "records.pb");
  EXPECT_EQ(v.code, 0) << v.output;
  const auto out = fresh_dir("mcap-export") / "rebuilt.mcap";
  std::filesystem::create_directories(out.parent_path());
  const Result e = run({bin("swarm"), "export", "--mcap", dir.string(), "--out", out.string()});
  ASSERT_EQ(e.code, 0) << e.output;
  EXPECT_NE(e.output.find(" records -> " + out.string()), std::string::npos) << e.output;
  EXPECT_TRUE(read_file(out) == read_file(dir / "run.mcap")) << "the export differs";
  const McapValidation ev = validate_mcap(out, dir / "records.pb");
  EXPECT_EQ(ev.code, 0) << ev.output;
}

TEST(Record, SwarmExportRefusesBadInputNamingItWithExit2) {
  const auto dir = fresh_dir("export-bad");
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "notes.txt") << "not a run\n";
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"export", "--mcap", (dir / "absent").string()}, "not a directory"},
      {{"export", "--mcap", dir.string()}, "not a run directory (it has no records.pb)"},
      {{"export"}, "--mcap"},
      {{"export", "--mcap", dir.string(), "--out", (dir / "no/such/x.mcap").string()}, "--out"},
  };
  for (const auto& [args, said] : cases) {
    std::vector<std::string> argv = {bin("swarm")};
    argv.insert(argv.end(), args.begin(), args.end());
    const Result r = run(argv);
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find(said), std::string::npos) << said << "\n" << r.output;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "run.mcap"));
}

// `--grace 0` kills every agent still running at teardown at once: an agent killed before it wrote
// its stats leaves the record incomplete. Exit 0 and "converged" only with every agent's stats
// there; otherwise exit 3, each missing file named, and a summary that is not "converged".
TEST(Record, GraceZeroNeverEndsConvergedWithAnAgentsStatsMissing) {
  for (const bool deaf : {false, true}) {
    const auto dir = fresh_dir(deaf ? "grace0-deaf" : "grace0");
    // With `deaf`, agent 3 ignores SIGTERM, so at least its stats are certainly missing.
    std::vector<std::string> extra = {"--grace", "0"};
    if (deaf) extra.insert(extra.end(), {"--test-ignore-sigterm", "3"});
    const Result r = swarm_run(scenario("faults_six"), dir, 4.0, extra);
    const records::Summary s = read_summary(dir);
    std::vector<unsigned> missing;
    for (unsigned id = 1; id <= 6; ++id)
      if (!std::filesystem::exists(dir / ("agent-" + std::to_string(id) + ".stats")))
        missing.push_back(id);
    if (deaf) EXPECT_NE(std::find(missing.begin(), missing.end(), 3u), missing.end());
    if (missing.empty()) {
      EXPECT_EQ(r.code, 0) << r.output;
      EXPECT_TRUE(s.converged()) << s.end_reason();
      continue;
    }
    EXPECT_EQ(r.code, 3) << r.output;
    EXPECT_FALSE(s.converged()) << s.end_reason();
    for (const unsigned id : missing) {
      const std::string named = "agent-" + std::to_string(id) + ".stats";
      EXPECT_NE(r.output.find(named), std::string::npos) << named << "\n" << r.output;
      EXPECT_NE(s.end_reason().find(named), std::string::npos) << s.end_reason();
    }
  }
}

TEST(Record, TwoRunsOnOneDomainKeepTheirOwnResultsAndEachSaysTheOtherWasThere) {
  // Two unrelated runs, same domain, at the same time: each must meet at its own average.
  const auto dir_a = fresh_dir("shared-domain-a"), dir_b = fresh_dir("shared-domain-b");
  Child a({bin("swarm"), "run", scenario("paper/unweighted"), "--out", dir_a.string(), "--domain",
           test_domain().str(), "--time-scale", "2", "--quiet"},
          dir_a.parent_path() / "shared-domain-a.log");
  Child b({bin("swarm"), "run", scenario("paper/weighted"), "--out", dir_b.string(), "--domain",
           test_domain().str(), "--time-scale", "2", "--quiet"},
          dir_b.parent_path() / "shared-domain-b.log");
  const Result ra = a.wait(240.0), rb = b.wait(240.0);
  ASSERT_EQ(ra.code, 0) << ra.output;
  ASSERT_EQ(rb.code, 0) << rb.output;
  const records::Summary sa = read_summary(dir_a), sb = read_summary(dir_b);
  expect_met_at(sa, Vec3(10.25, 9.75, 29.25), 0.01, true);  // paper 2.6.1
  expect_met_at(sb, Vec3(9, 12.75, 30.25), 0.01, true);     // paper 2.7.1
  EXPECT_LT(sa.average_drift_m(), 1e-3);
  EXPECT_LT(sb.average_drift_m(), 1e-3);
  EXPECT_NE(sa.run_id(), sb.run_id());
  // Each supervisor heard the other run while both flew, refused it, and said so.
  int noted = 0;
  for (const auto& dir : {dir_a, dir_b})
    for (const auto& row : read_csv(dir / "events.csv")) noted += row.at("kind") == "foreign_run";
  EXPECT_GE(noted, 1);
  EXPECT_GT(sa.foreign_samples() + sb.foreign_samples(), 0u);
}

TEST(Record, AFullFilesystemEndsTheRunNonZeroNamingTheFileNeverConverged) {
  if (geteuid() != 0) QSWARM_CANNOT_RUN("needs root to mount a small tmpfs");
  const auto mnt = fresh_dir("full-disk");
  std::filesystem::create_directories(mnt);
  if (run({"/bin/mount", "-t", "tmpfs", "-o", "size=256k", "tmpfs", mnt.string()}).code != 0)
    QSWARM_CANNOT_RUN("cannot mount a tmpfs here");
  const Result r = run({bin("swarm"), "run", scenario("demo"), "--out", (mnt / "run").string(),
                        "--domain", test_domain().str(), "--time-scale", "2", "--quiet"},
                       120.0);
  const mcap::FileCheck c = mcap::check_file(mnt / "run" / "run.mcap");
  run({"/bin/umount", "-l", mnt.string()});
  EXPECT_EQ(r.code, 3) << r.output;  // the record could not be written completely
  // It names a file of the run's record that it could not write.
  const auto at = r.output.find("could not write ");
  ASSERT_NE(at, std::string::npos) << r.output;
  const std::string named =
      r.output.substr(at + 16, r.output.find_first_of(" \n;", at + 16) - at - 16);
  const std::set<std::string> record = {"telemetry.csv", "graph.csv",  "events.csv",
                                        "records.pb",    "run.mcap",   "summary.json",
                                        "processes.csv", "plan.txtpb", "scenario.txtpb"};
  EXPECT_TRUE(record.count(std::filesystem::path(named).filename().string()))
      << "named \"" << named << "\": " << r.output;
  EXPECT_EQ(r.output.find("swarm run: converged"), std::string::npos) << r.output;
  // run.mcap, whichever file failed first, is never left cut short without saying so.
  if (!c.complete) EXPECT_NE(r.output.find("run.mcap"), std::string::npos) << r.output;
}

// The pids controller's root (cgroup v1 or v2) where this process may make a cgroup, or empty.
std::filesystem::path pids_cgroup_root() {
  if (std::filesystem::exists("/sys/fs/cgroup/pids/cgroup.procs")) return "/sys/fs/cgroup/pids";
  std::ifstream controllers("/sys/fs/cgroup/cgroup.controllers");
  std::string line;
  std::getline(controllers, line);
  if (line.find("pids") != std::string::npos) return "/sys/fs/cgroup";
  return {};
}

TEST(Record, AThreadLimitEndsTheRunNamingItWithNoAbortAndNoOrphan) {
  // A task limit (a cgroup's pids.max, what a container or a shared host sets) below what six
  // agents need: a launcher, a supervisor (about 8 threads) and 3 threads per agent (its tick
  // reads its sockets, Fast DDS's event and log threads). Agents that cannot make
  // their threads end with exit 1 and say why; the run is not converged, no child is reported
  // killed by a signal, and nothing is left running in the cgroup.
  if (geteuid() != 0) QSWARM_CANNOT_RUN("needs root to make a cgroup with a task limit");
  const std::filesystem::path root = pids_cgroup_root();
  if (root.empty()) QSWARM_CANNOT_RUN("no pids cgroup controller here");
  const std::filesystem::path cg = root / ("qswarm-test-" + std::to_string(getpid()));
  std::error_code ec;
  std::filesystem::create_directory(cg, ec);
  if (ec) QSWARM_CANNOT_RUN("cannot make a cgroup under " << root << ": " << ec.message());
  std::ofstream(cg / "pids.max") << 16 << std::flush;
  const auto dir = fresh_dir("thread-limit");
  std::filesystem::create_directories(dir);
  // The shell joins the cgroup, then becomes the launcher: every child is born inside.
  const Result r =
      run({"/bin/sh", "-c", "echo $$ > \"$0\" && exec \"$@\"", (cg / "cgroup.procs").string(),
           bin("swarm"), "run", scenario("faults_six"), "--out", (dir / "run").string(), "--domain",
           test_domain().str(), "--time-scale", "4", "--quiet",
           // The agents left cannot agree: 20 s of swarm time say so as well as the scenario's 120.
           "--duration", "20"},
          180.0);
  const bool emptied = wait_for([&] { return read_file(cg / "cgroup.procs").empty(); }, 10.0);
  const std::string left = read_file(cg / "cgroup.procs");
  const std::string events = read_file(cg / "pids.events");  // v1 and v2: "max N" refusals
  std::filesystem::remove(cg, ec);
  EXPECT_TRUE(emptied) << "processes left in the cgroup: " << left;
  EXPECT_NE(events.find("max "), std::string::npos);
  EXPECT_NE(events, "max 0\n") << "the limit never bit";
  // Not converged (1), or, when an agent starved of threads could not stop in time and write its
  // stats, a record that says it is incomplete (3), naming the file.
  EXPECT_TRUE(r.code == 1 || (r.code == 3 && r.output.find(".stats") != std::string::npos))
      << r.output;
  EXPECT_EQ(r.output.find("signal"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("swarm run: converged"), std::string::npos) << r.output;
  // Who ran out says so: an agent's (or the supervisor's) own line, or the launcher's fork.
  std::string said = r.output;
  for (const auto& f : std::filesystem::directory_iterator(dir / "run"))
    if (f.path().extension() == ".out") said += read_file(f.path());
  EXPECT_TRUE(said.find("out of threads or memory") != std::string::npos ||
              said.find("fork: Resource temporarily unavailable") != std::string::npos)
      << said;
  const records::Summary s = read_summary(dir / "run");
  EXPECT_FALSE(s.converged());
  EXPECT_FALSE(s.end_reason().empty());
}

}  // namespace
}  // namespace qswarm::test
