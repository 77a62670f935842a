// Agents started alike (swarm-agent --id auto, as compose starts its replicas) claim distinct ids
// over DDS; a replica given an id another one flies, or one replica too many, is refused with a
// message and the swarm flies on. Real processes on loopback, the supervisor recording into a
// fresh run directory it creates (--new-run-in, as in compose).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <memory>
#include <regex>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "tests/swarm/domain_lease.hpp"
#include "tests/swarm/harness.hpp"

namespace qswarm::test {
namespace {

std::set<unsigned> ids_flown(const std::filesystem::path& dir, int n) {
  std::set<unsigned> ids;
  const std::regex flies("flies as agent ([0-9]+)");
  for (int k = 0; k < n; ++k) {
    const std::string text = read_file(dir / ("replica-" + std::to_string(k) + ".out"));
    std::smatch m;
    if (std::regex_search(text, m, flies)) ids.insert(static_cast<unsigned>(std::stoul(m[1])));
  }
  return ids;
}

// The four replicas' scenario (seeded random agents) in `dir`, with `law` after the mode and
// the duration.
std::filesystem::path claim_scenario(const std::filesystem::path& dir, const std::string& law,
                                     int duration_s) {
  const auto scen = dir / "swarm.txtpb";
  std::ofstream(scen) << "name: \"claim\"\n"
                         "random_agents { count: 4 box_m: 30 }\n"
                         "mode: PARTICLE "
                      << law
                      << "\n"
                         "weight { policy: UNWEIGHTED }\n"
                         "topology { policy: PROXIMITY threshold_m: 1000 }\n"
                         "convergence { tolerance_m: 1e-8 hold_s: 1 }\n"
                         "duration_s: "
                      << duration_s << " seed: 5\n";
  return scen;
}

// `argv`, the flags every process of the claim runs shares, then `more`.
std::vector<std::string> claim_argv(std::vector<std::string> argv,
                                    const std::filesystem::path& scen,
                                    const std::vector<std::string>& more) {
  for (const std::string& a : {std::string("--scenario"), scen.string(), std::string("--domain"),
                               test_domain().str(), std::string("--agents"), std::string("4")})
    argv.push_back(a);
  argv.insert(argv.end(), more.begin(), more.end());
  return argv;
}

TEST(IdClaimRun, ReplicasStartedAlikeFlyDistinctIdsAndDuplicatesAreRefused) {
  const auto dir = fresh_dir("id-claim");
  std::filesystem::create_directories(dir / "runs");
  const auto scen = claim_scenario(dir, "law: EDGE_FLOW", 60);
  const auto with = [&](std::vector<std::string> argv, const std::vector<std::string>& more) {
    return claim_argv(std::move(argv), scen, more);
  };
  Child sup(with({bin("swarm-supervisor")}, {"--new-run-in", (dir / "runs").string()}),
            dir / "supervisor.out");
  std::vector<std::unique_ptr<Child>> agents;
  agents.reserve(4);
  for (int k = 0; k < 4; ++k)
    agents.push_back(
        std::make_unique<Child>(with({bin("swarm-agent")}, {"--id", "auto", "--wait-supervisor"}),
                                dir / ("replica-" + std::to_string(k) + ".out")));
  ASSERT_TRUE(wait_for([&] { return ids_flown(dir, 4).size() == 4; }, 60.0))
      << "the four replicas did not all take an id";
  EXPECT_EQ(ids_flown(dir, 4), (std::set<unsigned>{1, 2, 3, 4}));

  // A fifth replica told to fly agent 2, and a sixth one with --id auto: both refused, exit 2.
  Child dup(with({bin("swarm-agent")}, {"--id", "2", "--claim"}), dir / "dup.out");
  Child extra(with({bin("swarm-agent")}, {"--id", "auto"}), dir / "extra.out");
  const Result d = dup.wait(60.0);
  EXPECT_EQ(d.code, 2) << d.output;
  EXPECT_NE(d.output.find("agent id 2 is already held by another replica"), std::string::npos)
      << d.output;
  const Result e = extra.wait(60.0);
  EXPECT_EQ(e.code, 2) << e.output;
  EXPECT_NE(e.output.find("more replicas than the swarm's 4 agents"), std::string::npos)
      << e.output;

  const Result s = sup.wait(120.0);
  EXPECT_EQ(s.code, 0) << s.output;
  for (auto& a : agents) a->signal(SIGINT);
  for (auto& a : agents) EXPECT_EQ(a->wait(30.0).code, 0);

  std::filesystem::path run;
  for (const auto& entry : std::filesystem::directory_iterator(dir / "runs")) run = entry.path();
  ASSERT_FALSE(run.empty()) << "no run directory under " << dir / "runs";
  const records::Summary sum = read_summary(run);
  EXPECT_TRUE(sum.converged()) << sum.end_reason();
  EXPECT_EQ(sum.agents_size(), 4);
  EXPECT_EQ(sum.missing_agents_size(), 0);
  EXPECT_LT(sum.average_relative_error(), 1e-9);
  EXPECT_TRUE(std::filesystem::exists(run / "scenario.txtpb"));
}

// The secure compose swarm, as processes: replicas share a compose keystore's member identity
// (swarm keys --compose), claim their ids and fly; a stranger without it, started as agent 3 of
// the same scenario (the same run id: compose runs have no launcher to make one), publishes as
// agent 3 throughout and is heard by no one. A replica that claims its id with a per-agent
// keystore is refused before it flies.
TEST(IdClaimRun, ReplicasWithAComposeKeystoreFlyAndAStrangerWithoutItIsHeardByNoOne) {
  const auto dir = fresh_dir("id-claim-secure");
  std::filesystem::create_directories(dir / "runs");
  const auto scen = claim_scenario(dir, "law: EDGE_FLOW gain: 0.3", 90);
  const auto keys = [&](const std::string& name, std::vector<std::string> more) {
    std::vector<std::string> argv = {bin("swarm"), "keys", scen.string(), "--out",
                                     (dir / name).string()};
    argv.insert(argv.end(), more.begin(), more.end());
    const Result r = run(argv, 60.0);
    EXPECT_EQ(r.code, 0) << r.output;
    return (dir / name).string();
  };
  const std::string compose = keys("compose-keys", {"--compose"});
  const std::string per_agent = keys("agent-keys", {});
  const auto with = [&](std::vector<std::string> argv, const std::vector<std::string>& more) {
    return claim_argv(std::move(argv), scen, more);
  };
  // Claiming with a per-agent keystore: refused, exit 2, nothing flown.
  const Result refused =
      run(with({bin("swarm-agent")}, {"--id", "auto", "--keystore", per_agent}), 60.0);
  EXPECT_EQ(refused.code, 2) << refused.output;
  EXPECT_NE(refused.output.find("needs a compose keystore"), std::string::npos) << refused.output;

  // Secure processes on one host discover by unicast within a block of the port plan, as swarm
  // run starts them (docs/security.md, "Discovery by unicast"): the
  // supervisor takes id 0, the replicas 1 to 4 and the stranger 5, announcing to all six.
  const auto place = [](int id) {
    return std::vector<std::string>{"--participant-id", std::to_string(id), "--unicast-peers",
                                    "0:6"};
  };
  const auto also = [](std::vector<std::string> a, const std::vector<std::string>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
  };
  Child stranger(with({bin("swarm-agent")}, also({"--id", "3", "--start-timeout", "3"}, place(5))),
                 dir / "stranger.out");
  Child sup(with({bin("swarm-supervisor")},
                 also({"--new-run-in", (dir / "runs").string(), "--keystore", compose}, place(0))),
            dir / "supervisor.out");
  std::vector<std::unique_ptr<Child>> agents;
  agents.reserve(4);
  for (int k = 0; k < 4; ++k)
    agents.push_back(std::make_unique<Child>(
        with({bin("swarm-agent")},
             also({"--id", "auto", "--wait-supervisor", "--keystore", compose}, place(k + 1))),
        dir / ("replica-" + std::to_string(k) + ".out")));
  ASSERT_TRUE(wait_for([&] { return ids_flown(dir, 4).size() == 4; }, 90.0))
      << "the four replicas did not all take an id";
  EXPECT_EQ(ids_flown(dir, 4), (std::set<unsigned>{1, 2, 3, 4}));
  const Result s = sup.wait(180.0);
  EXPECT_EQ(s.code, 0) << s.output;
  for (auto& a : agents) a->signal(SIGINT);
  for (auto& a : agents) EXPECT_EQ(a->wait(30.0).code, 0);
  stranger.signal(SIGINT);
  const Result st = stranger.wait(30.0);
  // It flew alone: its barrier heard none of the replicas.
  EXPECT_NE(st.output.find("start timeout: 0 of 3 peers ready"), std::string::npos) << st.output;

  std::filesystem::path run;
  for (const auto& entry : std::filesystem::directory_iterator(dir / "runs")) run = entry.path();
  ASSERT_FALSE(run.empty()) << "no run directory under " << dir / "runs";
  const records::Summary sum = read_summary(run);
  EXPECT_TRUE(sum.secure());
  EXPECT_TRUE(sum.converged()) << sum.end_reason();
  EXPECT_EQ(sum.agents_size(), 4);
  EXPECT_EQ(sum.forgeries_size(), 0);
  EXPECT_LT(sum.average_relative_error(), 1e-9);
  for (const auto& row : read_csv(run / "events.csv")) EXPECT_NE(row.at("kind"), "forgery");
}

}  // namespace
}  // namespace qswarm::test
