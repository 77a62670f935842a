// DDS-Security as an attacker would try it: participants with the keystore's identities hear each
// other; a stranger without credentials, or with a certificate from another authority, publishing
// well-formed samples with the run's id on its partition, reaches no one and hears nothing. The
// keystores are made by the product's own `swarm keys`.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <set>

#include "common/dds/dds_bus.hpp"
#include "tests/dds/test_bus.hpp"
#include "tests/swarm/domain_lease.hpp"
#include "tests/swarm/harness.hpp"

namespace qswarm {
namespace {

namespace fs = std::filesystem;
constexpr std::uint64_t kRun = 0x5EC;

class Security : public ::testing::Test {
 protected:
  // Per process: ctest runs each test in a process of its own, two at a time.
  static std::string mine(const char* what) { return what + std::to_string(::getpid()); }
  static fs::path ours() { return test::fresh_dir_path(mine("security-")) / "ours"; }
  static fs::path foreign() { return test::fresh_dir_path(mine("security-")) / "foreign"; }

  // The keystores, made once per process (a failure here fails the test, not skips it).
  void SetUp() override {
    static bool made = false;
    if (made) return;
    test::fresh_dir(mine("security-"));
    for (const fs::path& ks : {ours(), foreign()}) {
      const test::Result r = test::run(
          {test::bin("swarm"), "keys", test::scenario("demo"), "--out", ks.string()}, 60.0);
      ASSERT_EQ(r.code, 0) << r.output;
    }
    made = true;
  }

  // A participant of run kRun; `keystore` empty: a plain one.
  static DdsOptions options(const char* name, const fs::path& keystore, const std::string& identity,
                            bool recorder = false) {
    DdsOptions o = test::dds_options(name, kRun, recorder);
    o.participant.keystore = keystore.string();
    o.participant.identity = identity;
    return o;
  }

  static StateMessage sample(AgentId id, std::uint64_t seq) {
    return test::state_sample(id, kRun, seq);
  }

  static std::set<AgentId> heard(DdsBus& bus) {
    std::set<AgentId> ids;
    for (const StateMessage& m : bus.latest(0)) ids.insert(m.view.id);
    return ids;
  }

  // Agent 1 publishes (state and record) beside an intruder publishing as `intruder_id`, until
  // agent 2 and the supervisor have each taken 50 of agent 1's samples: the intruder has had as
  // long to get through as the agents needed to hear each other, many times over.
  static void fly_beside(DdsBus& intruder, AgentId intruder_id) {
    DdsBus agent1(options("agent-1", ours(), "agent-1"));
    DdsBus agent2(options("agent-2", ours(), "agent-2"));
    DdsBus supervisor(options("supervisor", ours(), "supervisor", true));
    std::uint64_t seq = 0;
    ASSERT_TRUE(test::wait_for(
        [&] {
          ++seq;
          agent1.publish(sample(1, seq));
          agent1.record(sample(1, seq));
          intruder.publish(sample(intruder_id, seq));
          intruder.record(sample(intruder_id, seq));
          return agent2.counters().received >= 50 && supervisor.counters().received >= 50;
        },
        60.0));
    EXPECT_EQ(heard(agent2), std::set<AgentId>{1});
    EXPECT_EQ(heard(supervisor), std::set<AgentId>{1});
    EXPECT_EQ(agent2.counters().dropped + agent2.counters().foreign, 0u);
    // Nor does the intruder hear the run (only its own samples, through its own participant):
    // discovery and samples are encrypted for members only.
    EXPECT_EQ(heard(intruder), std::set<AgentId>{intruder_id});
  }
};

TEST_F(Security, AStrangerWithoutCredentialsReachesNoOneAndHearsNothing) {
  // A plain participant that knows the run id, on the run's partitions, as agent 3.
  DdsOptions o = options("stranger", {}, "");
  o.state.hear_all_runs = true;
  DdsBus stranger(o);
  fly_beside(stranger, 3);
}

TEST_F(Security, ACertificateFromAnotherAuthorityIsRefused) {
  // A well-formed identity, permissions and governance for agent 3, all signed by another CA.
  DdsOptions o = options("foreign-agent-3", foreign(), "agent-3");
  o.state.hear_all_runs = true;
  DdsBus outsider(o);
  fly_beside(outsider, 3);
}

TEST_F(Security, ABadKeystoreStopsTheRunBeforeAnythingFliesNamingTheFile) {
  const fs::path runs = test::fresh_dir(mine("security-runs-"));
  fs::create_directories(runs);
  const auto secure_run = [&](const fs::path& keystore, const std::string& name) {
    return test::run(
        {test::bin("swarm"), "run", test::scenario("demo"), "--secure", keystore.string(), "--out",
         (runs / name).string(), "--domain", test::test_domain().str()},
        60.0);
  };
  // Missing.
  test::Result r = secure_run(runs / "nowhere", "missing");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("transport.keystore"), std::string::npos) << r.output;
  // Another scenario's keystore lacks an agent: a copy without agent-4.
  const fs::path partial = runs / "partial";
  fs::copy(ours(), partial, fs::copy_options::recursive);
  fs::remove_all(partial / "agent-4");
  r = secure_run(partial, "partial");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("agent-4/cert.pem"), std::string::npos) << r.output;
  // Tampered: agent 2's permissions widened after signing.
  const fs::path tampered = runs / "tampered";
  fs::copy(ours(), tampered, fs::copy_options::recursive);
  std::string p7s = test::read_file(tampered / "agent-2" / "permissions.p7s");
  const std::size_t at = p7s.find("qswarm-record-*");
  ASSERT_NE(at, std::string::npos);
  p7s.replace(at, 15, "***************");
  std::ofstream(tampered / "agent-2" / "permissions.p7s", std::ios::trunc) << p7s;
  r = secure_run(tampered, "tampered");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("agent-2/permissions.p7s"), std::string::npos) << r.output;
  // Nothing flew: no run directory holds a record.
  for (const char* name : {"missing", "partial", "tampered"})
    EXPECT_FALSE(fs::exists(runs / name / "summary.json")) << name;
}

}  // namespace
}  // namespace qswarm
