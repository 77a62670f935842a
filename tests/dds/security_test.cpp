// DDS-Security as an attacker would try it: participants with the keystore's identities hear each
// other; a stranger without credentials, or with a certificate from another authority, publishing
// well-formed samples with the run's id on its partition, reaches no one and hears nothing. The
// keystores are made by the product's own `swarm keys`.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>

#include "common/dds/dds_bus.hpp"
#include "common/transport/port_plan.hpp"
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

  // A participant of run kRun flying agent `self` (0: none); `keystore` empty: a plain one. It
  // takes participant id `id` of a block of four (the members, then the intruder) and discovers
  // by unicast alone within it, as a secure run does: with multicast beside unicast, Fast DDS
  // 2.9.1 can leave a secure pair unpaired for good (participant.hpp), and a test that waits for
  // the members to hear each other would then fail for a reason that is not the one it tests.
  static constexpr int kBlock = 100;
  static DdsOptions options(const char* name, const fs::path& keystore, const std::string& identity,
                            int id, bool recorder = false, AgentId self = 0) {
    DdsOptions o = test::dds_options(name, kRun, recorder);
    o.participant.keystore = keystore.string();
    o.participant.identity = identity;
    o.participant.participant_id = kBlock + id;
    o.participant.unicast_peers_first = kBlock;
    o.participant.unicast_peers_count = 4;
    o.state.self = self;
    return o;
  }
  static constexpr int kIntruder = 3;  // the intruder's place in the block

  static StateMessage sample(AgentId id, std::uint64_t seq) {
    return test::state_sample(id, kRun, seq);
  }

  static std::set<AgentId> heard(DdsBus& bus) {
    std::set<AgentId> ids;
    for (const StateMessage& m : bus.latest(0)) ids.insert(m.view.id);
    return ids;
  }

  // Agents 1 and 2 publish until each has heard the other; whether that happened within a minute.
  static bool meet(DdsBus& agent1, DdsBus& agent2) {
    std::uint64_t seq = 0;
    return test::wait_for(
        [&] {
          ++seq;
          agent1.publish(sample(1, seq));
          agent2.publish(sample(2, seq));
          return heard(agent1).count(2) == 1 && heard(agent2).count(1) == 1;
        },
        60.0);
  }

  // Agent 1 and an intruder with agent 3's certificate publish as themselves, one sample each
  // (`seq` counts them), until `cond` holds; whether it did within a minute.
  static bool beside(DdsBus& agent1, DdsBus& intruder, std::uint64_t& seq,
                     const std::function<bool()>& cond) {
    return test::wait_for(
        [&] {
          ++seq;
          agent1.publish(sample(1, seq));
          intruder.publish(sample(3, seq));
          return cond();
        },
        60.0);
  }

  // Agents 1 and 2 and the supervisor of the run, every one with its own certificate.
  struct Members {
    DdsBus agent1{options("agent-1", ours(), "agent-1", 0, false, 1)};
    DdsBus agent2{options("agent-2", ours(), "agent-2", 1, false, 2)};
    DdsBus supervisor{options("supervisor", ours(), "supervisor", 2, true)};

    // Agent 1 publishes (state and record) beside an intruder publishing as `intruder_id`, until
    // agent 2 and the supervisor have each taken 50 of agent 1's samples and `also` holds: the
    // intruder has had as long to get through as the agents needed to hear each other, many
    // times over. Returns whether that happened within a minute.
    bool fly_beside(
        DdsBus& intruder, AgentId intruder_id,
        const std::function<bool()>& also = [] { return true; }) {
      std::uint64_t seq = 0;
      return test::wait_for(
          [&] {
            ++seq;
            agent1.publish(sample(1, seq));
            agent1.record(sample(1, seq));
            intruder.publish(sample(intruder_id, seq));
            intruder.record(sample(intruder_id, seq));
            return agent2.counters().received >= 50 && supervisor.counters().received >= 50 &&
                   also();
          },
          60.0);
    }
  };

  // An outsider publishing as `intruder_id` reaches no one and hears nothing of the run.
  static void expect_shut_out(DdsBus& intruder, AgentId intruder_id) {
    Members run;
    ASSERT_TRUE(run.fly_beside(intruder, intruder_id));
    EXPECT_EQ(heard(run.agent2), std::set<AgentId>{1});
    EXPECT_EQ(heard(run.supervisor), std::set<AgentId>{1});
    EXPECT_EQ(run.agent2.counters().dropped + run.agent2.counters().foreign, 0u);
    // Nor does the intruder hear the run (only its own samples, through its own participant):
    // discovery and samples are encrypted for members only.
    EXPECT_EQ(heard(intruder), std::set<AgentId>{intruder_id});
  }
};

TEST_F(Security, AStrangerWithoutCredentialsReachesNoOneAndHearsNothing) {
  // A plain participant that knows the run id, on the run's partitions, as agent 3.
  DdsOptions o = options("stranger", {}, "", kIntruder);
  o.state.hear_all_runs = true;
  DdsBus stranger(o);
  expect_shut_out(stranger, 3);
}

// Secure processes of a run discover by unicast alone within the run's block (Fast DDS 2.9.1 can
// leave a secure pair unpaired when multicast and unicast discovery run at once; docs/security.md).
// Two members told each other's ids meet and hear each other with no multicast at all.
TEST_F(Security, MembersToldTheirBlockMeetByUnicastAlone) {
  DdsBus agent1(options("agent-1", ours(), "agent-1", 0, false, 1));
  DdsBus agent2(options("agent-2", ours(), "agent-2", 1, false, 2));
  EXPECT_TRUE(meet(agent1, agent2));
  // No multicast discovery socket: the domain's multicast port is not bound by this process.
  const std::uint32_t multicast = PortPlan::discovery_multicast_port(test::test_domain().domain());
  EXPECT_FALSE(this_process_holds_udp_port(multicast));
  // (A participant left to Fast DDS's defaults listens there: the check can see it.)
  DdsBus plain(test::dds_options("plain", kRun));
  EXPECT_TRUE(this_process_holds_udp_port(multicast));
}

// Compose replicas have no interface address of their own to announce to: they are told their
// peers' host addresses (find_peer_hosts, from the services' names) and discover by unicast there,
// at the ids' ports of each host, with no multicast.
TEST_F(Security, MembersToldTheirPeersHostsMeetByUnicastAlone) {
  const auto at_hosts = [](const char* name, int id, AgentId self) {
    DdsOptions o = options(name, ours(), name, id, false, self);
    o.participant.unicast_peer_hosts = {"127.0.0.1"};
    return o;
  };
  DdsBus agent1(at_hosts("agent-1", 0, 1));
  DdsBus agent2(at_hosts("agent-2", 1, 2));
  EXPECT_TRUE(meet(agent1, agent2));
  EXPECT_FALSE(this_process_holds_udp_port(
      PortPlan::discovery_multicast_port(test::test_domain().domain())));
  // A peer host that is not an address (a name left unresolved) is refused, named.
  DdsOptions bad = at_hosts("agent-3", 2, 3);
  bad.participant.unicast_peer_hosts = {"agent"};
  try {
    DdsBus bus(bad);
    FAIL() << "a name was taken as a peer host's address";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("\"agent\""), std::string::npos) << e.what();
  }
}

TEST_F(Security, ACertificateFromAnotherAuthorityIsRefused) {
  // A well-formed identity, permissions and governance for agent 3, all signed by another CA.
  DdsOptions o = options("foreign-agent-3", foreign(), "agent-3", kIntruder);
  o.state.hear_all_runs = true;
  DdsBus outsider(o);
  expect_shut_out(outsider, 3);
}

// A member of the run holding agent 3's certificate publishes state and record samples keyed as
// agent 5. Its writers are in agent 3's partitions (its permissions allow no other), so every
// reader refuses them; it still hears the run (it is a member), so it is the binding, not
// authentication, that refuses it.
TEST_F(Security, AMemberWithAgent3sCertificatePublishingAsAgent5IsRefusedByEveryReader) {
  DdsBus intruder(options("agent-3-as-5", ours(), "agent-3", kIntruder, false, 3));
  Members run;
  DdsBus& agent2 = run.agent2;
  DdsBus& supervisor = run.supervisor;
  // Agent 1 heard, the intruder's samples arrived and were refused (not lost), and the intruder
  // (a member) heard agent 1: waited for, since its reader may match after the others'.
  bool intruder_heard_the_run = false;
  ASSERT_TRUE(run.fly_beside(intruder, 5,
                             [&] {
                               intruder_heard_the_run =
                                   intruder_heard_the_run || heard(intruder).count(1) == 1;
                               return agent2.counters().dropped >= 20 &&
                                      supervisor.counters().dropped >= 5 && intruder_heard_the_run;
                             }))
      << "agent 2 took " << agent2.counters().received << " and refused "
      << agent2.counters().dropped << "; the supervisor took " << supervisor.counters().received
      << " and refused " << supervisor.counters().dropped << "; a member, the intruder "
      << (intruder_heard_the_run ? "heard" : "never heard") << " agent 1";
  EXPECT_EQ(heard(agent2), std::set<AgentId>{1});
  EXPECT_EQ(heard(supervisor), std::set<AgentId>{1});
  EXPECT_EQ(agent2.suspects(), (std::map<AgentId, std::uint8_t>{{5, kBoundElsewhere}}));
  EXPECT_EQ(supervisor.suspects(), (std::map<AgentId, std::uint8_t>{{5, kBoundElsewhere}}));
}

// The same member first publishes as itself, then moves its writer into agent 5's partition and
// publishes as 5 (and as 3). Fast DDS 2.9.1 refuses the new partitions but keeps the match it had;
// the readers then refuse every sample of that writer, for good.
TEST_F(Security, AWriterThatMovesIntoAnotherAgentsPartitionIsRefusedForGood) {
  DdsBus intruder(options("agent-3", ours(), "agent-3", kIntruder, false, 3));
  DdsBus agent1(options("agent-1", ours(), "agent-1", 0, false, 1));
  DdsBus agent2(options("agent-2", ours(), "agent-2", 1, false, 2));
  // Agent 2 listens to agents 1, 3 and 5 by name, so that it still matches the moved writer.
  agent2.set_interest(Interest{{}, {"a1", "a3", "a5"}, {}});
  std::uint64_t seq = 0;
  ASSERT_TRUE(beside(agent1, intruder, seq, [&] {
    return heard(agent2) == std::set<AgentId>{1, 3};
  }));
  const std::uint64_t moved_at = seq;
  intruder.set_interest(Interest{{"a5"}, {}, {}});
  const std::uint64_t received = agent2.counters().received;
  ASSERT_TRUE(test::wait_for(
      [&] {
        ++seq;
        agent1.publish(sample(1, seq));
        intruder.publish(sample(5, seq));
        intruder.publish(sample(3, seq));
        return agent2.counters().received >= received + 50 && agent2.counters().dropped >= 20;
      },
      60.0))
      << "refused " << agent2.counters().dropped;
  EXPECT_EQ(heard(agent2), (std::set<AgentId>{1, 3}));
  for (const StateMessage& m : agent2.latest(0))
    if (m.view.id == 3) {
      EXPECT_LE(m.seq, moved_at + 5) << "agent 3's moved writer was heard";
    }
}

// A member that publishes into the pattern "*" beside its own partition: its permissions admit the
// pattern (it names no agent), and Fast DDS matches partitions with fnmatch both ways, so its
// writer reaches agent 2's reader that listens to agent 1 alone. That reader refuses it.
TEST_F(Security, AWriterInAPartitionPatternIsRefusedByAReaderItReaches) {
  DdsBus intruder(options("agent-3", ours(), "agent-3", kIntruder, false, 3));
  DdsBus agent1(options("agent-1", ours(), "agent-1", 0, false, 1));
  DdsBus agent2(options("agent-2", ours(), "agent-2", 1, false, 2));
  agent2.set_interest(Interest{{}, {"a1"}, {}});
  intruder.set_interest(Interest{{"*"}, {}, {}});
  std::uint64_t seq = 0;
  ASSERT_TRUE(
      beside(agent1, intruder, seq,
             [&] { return heard(agent2).count(1) == 1 && agent2.counters().dropped >= 20; }))
      << "agent 2 took " << agent2.counters().received << " and refused "
      << agent2.counters().dropped;
  EXPECT_EQ(heard(agent2), std::set<AgentId>{1});
  EXPECT_EQ(agent2.suspects(), (std::map<AgentId, std::uint8_t>{{3, kBoundElsewhere}}));
}

// The same member, heard first by name as itself, then moving its writer into "*" as well: from
// then on agent 2 refuses it, though it still names only agent 3.
TEST_F(Security, AWriterThatMovesIntoAPartitionPatternIsRefusedForGood) {
  DdsBus intruder(options("agent-3", ours(), "agent-3", kIntruder, false, 3));
  DdsBus agent2(options("agent-2", ours(), "agent-2", 1, false, 2));
  agent2.set_interest(Interest{{}, {"a3"}, {}});
  std::uint64_t seq = 0;
  ASSERT_TRUE(test::wait_for(
      [&] {
        intruder.publish(sample(3, ++seq));
        return heard(agent2) == std::set<AgentId>{3};
      },
      60.0));
  const std::uint64_t moved_at = seq;
  intruder.set_interest(Interest{{"*"}, {}, {}});
  ASSERT_TRUE(test::wait_for(
      [&] {
        intruder.publish(sample(3, ++seq));
        return agent2.counters().dropped >= 20;
      },
      60.0))
      << "agent 2 took " << agent2.counters().received << " and refused "
      << agent2.counters().dropped;
  for (const StateMessage& m : agent2.latest(0)) {
    EXPECT_EQ(m.view.id, 3u);
    EXPECT_LE(m.seq, moved_at + 5) << "agent 3's writer was heard in the pattern";
  }
  EXPECT_EQ(agent2.suspects(), (std::map<AgentId, std::uint8_t>{{3, kBoundElsewhere}}));
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
  const std::size_t at = p7s.find("/a2<");
  ASSERT_NE(at, std::string::npos);
  p7s.replace(at, 3, "/a*");
  std::ofstream(tampered / "agent-2" / "permissions.p7s", std::ios::trunc) << p7s;
  r = secure_run(tampered, "tampered");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("agent-2/permissions.p7s"), std::string::npos) << r.output;
  // Signed by the authority, but agent 2's permissions bind it to no partition of its own (as an
  // older `swarm keys` wrote them): readers could not tell its samples from another agent's.
  const fs::path unbound = runs / "unbound";
  fs::copy(ours(), unbound, fs::copy_options::recursive);
  std::string xml = test::read_file(unbound / "agent-2" / "permissions.xml");
  for (std::size_t a2 = xml.find("/a2<"); a2 != std::string::npos; a2 = xml.find("/a2<"))
    xml.replace(a2, 3, "/q2");
  std::ofstream(unbound / "agent-2" / "permissions.xml", std::ios::trunc) << xml;
  const test::Result signed_again = test::run(
      {"/usr/bin/openssl", "smime", "-sign", "-text", "-in",
       (unbound / "agent-2" / "permissions.xml").string(), "-out",
       (unbound / "agent-2" / "permissions.p7s").string(), "-signer",
       (unbound / "ca.cert.pem").string(), "-inkey", (unbound / "private" / "ca.key.pem").string()},
      60.0);
  ASSERT_EQ(signed_again.code, 0) << signed_again.output;
  r = secure_run(unbound, "unbound");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("agent-2/permissions.p7s: permissions that do not bind agent-2"),
            std::string::npos)
      << r.output;
  // A compose keystore (one member identity, for replicas that claim their ids).
  const fs::path compose = runs / "compose-keys";
  const test::Result k = test::run(
      {test::bin("swarm"), "keys", test::scenario("demo"), "--compose", "--out", compose.string()},
      60.0);
  ASSERT_EQ(k.code, 0) << k.output;
  r = secure_run(compose, "compose");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("a compose keystore"), std::string::npos) << r.output;
  // Agent 2's and agent 3's identities swapped (each certificate with its own key).
  const fs::path swapped = runs / "swapped";
  fs::copy(ours(), swapped, fs::copy_options::recursive);
  fs::rename(swapped / "agent-2", swapped / "agent-x");
  fs::rename(swapped / "agent-3", swapped / "agent-2");
  fs::rename(swapped / "agent-x", swapped / "agent-3");
  r = secure_run(swapped, "swapped");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("agent-2/cert.pem: the certificate of agent-3"), std::string::npos)
      << r.output;
  // A private key anyone may read, in a directory anyone may write.
  const fs::path open = runs / "open";
  fs::copy(ours(), open, fs::copy_options::recursive);
  fs::permissions(open / "agent-1" / "key.pem", fs::perms::all);
  r = secure_run(open, "open");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("agent-1/key.pem: a private key readable by others"), std::string::npos)
      << r.output;
  // The supervisor's certificate a link to one outside the keystore.
  const fs::path linked = runs / "linked";
  fs::copy(ours(), linked, fs::copy_options::recursive);
  fs::rename(linked / "supervisor" / "cert.pem", runs / "supervisor-cert.pem");
  fs::create_symlink(runs / "supervisor-cert.pem", linked / "supervisor" / "cert.pem");
  r = secure_run(linked, "linked");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("supervisor/cert.pem: a link out of the keystore"), std::string::npos)
      << r.output;
  // Nothing flew: no run directory holds a record.
  for (const char* name :
       {"missing", "partial", "tampered", "unbound", "compose", "swapped", "open", "linked"})
    EXPECT_FALSE(fs::exists(runs / name / "summary.json")) << name;
}

// A compose replica has no launcher to check its keystore: the agent itself refuses a member
// certificate that expired or is not one, naming the file, instead of failing to make a
// participant.
TEST_F(Security, AComposeReplicaWithAnExpiredOrBrokenCertificateExits2NamingIt) {
  const fs::path dir = test::fresh_dir(mine("security-member-"));
  const fs::path ks = dir / "keys";
  fs::create_directories(dir);
  const test::Result k = test::run(
      {test::bin("swarm"), "keys", test::scenario("demo"), "--compose", "--out", ks.string()},
      60.0);
  ASSERT_EQ(k.code, 0) << k.output;
  const fs::path cert = ks / "member" / "cert.pem";
  const auto replica = [&] {
    return test::run({test::bin("swarm-agent"), "--scenario", test::scenario("demo"), "--id",
                      "auto", "--keystore", ks.string(), "--domain", test::test_domain().str()},
                     60.0);
  };
  // The member's own key, certified by the keystore's authority for one day in 2020.
  const fs::path db = dir / "ca-db";
  fs::create_directories(db);
  std::ofstream(db / "index.txt");
  std::ofstream(db / "serial") << "01\n";
  std::ofstream(dir / "ca.cnf")
      << "[ca]\ndefault_ca = c\n[c]\ndatabase = " << (db / "index.txt").string()
      << "\nnew_certs_dir = " << db.string() << "\nserial = " << (db / "serial").string()
      << "\ndefault_md = sha256\npolicy = p\n[p]\ncommonName = supplied\n";
  const std::string openssl = "/usr/bin/openssl";
  test::Result o = test::run({openssl, "req", "-new", "-key", (ks / "member" / "key.pem").string(),
                              "-subj", "/CN=member", "-out", (dir / "member.csr").string()},
                             60.0);
  ASSERT_EQ(o.code, 0) << o.output;
  o = test::run(
      {openssl, "ca", "-batch", "-config", (dir / "ca.cnf").string(), "-cert",
       (ks / "ca.cert.pem").string(), "-keyfile", (ks / "private" / "ca.key.pem").string(), "-in",
       (dir / "member.csr").string(), "-out", cert.string(), "-startdate", "20200101000000Z",
       "-enddate", "20200102000000Z"},
      60.0);
  ASSERT_EQ(o.code, 0) << o.output;
  test::Result r = replica();
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("member/cert.pem: expired"), std::string::npos) << r.output;
  std::ofstream(cert, std::ios::trunc) << "not a certificate\n";
  r = replica();
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("member/cert.pem: not a PEM certificate"), std::string::npos) << r.output;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace qswarm
