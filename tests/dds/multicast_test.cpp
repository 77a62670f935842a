// Where everyone hears everyone, a state sample leaves its writer once, to the domain's multicast
// group, instead of once per reader; and the runs that must not use the group do not.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "common/app/process_dds.hpp"
#include "common/app/process_life.hpp"
#include "common/dds/dds_bus.hpp"
#include "common/scenario/scenario.hpp"
#include "common/transport/port_plan.hpp"
#include "tests/dds/test_bus.hpp"
#include "tests/swarm/domain_lease.hpp"
#include "tests/swarm/harness.hpp"

namespace qswarm {
namespace {

constexpr std::uint64_t kRun = 0x3c;

// A plain socket that listens at the group and port the state readers use, as one more member:
// it counts the RTPS datagrams the writers send there (none unless they send to the group).
class GroupListener {
 public:
  GroupListener(const char* group, std::uint32_t port) : fd_(::socket(AF_INET, SOCK_DGRAM, 0)) {
    if (fd_ < 0) throw std::runtime_error(std::strerror(errno));
    const int on = 1;
    ::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
    timeval tv{0, 100000};
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    sockaddr_in at{};
    at.sin_family = AF_INET;
    at.sin_port = htons(static_cast<std::uint16_t>(port));
    ::inet_pton(AF_INET, group, &at.sin_addr);  // as Fast DDS binds: the group's datagrams only
    if (::bind(fd_, reinterpret_cast<sockaddr*>(&at), sizeof at) != 0)
      throw std::runtime_error(std::string("bind: ") + std::strerror(errno));
    ip_mreq join{};
    ::inet_pton(AF_INET, group, &join.imr_multiaddr);
    ::inet_pton(AF_INET, "127.0.0.1", &join.imr_interface);
    if (::setsockopt(fd_, IPPROTO_IP, IP_ADD_MEMBERSHIP, &join, sizeof join) != 0)
      throw std::runtime_error(std::string("join: ") + std::strerror(errno));
  }
  ~GroupListener() { ::close(fd_); }
  GroupListener(const GroupListener&) = delete;
  GroupListener& operator=(const GroupListener&) = delete;

  // RTPS datagrams received within about 0.1 s.
  int drain() {
    int n = 0;
    char buf[65536];
    for (;;) {
      const ssize_t got = ::recv(fd_, buf, sizeof buf, 0);
      if (got < 0) return n;
      if (got >= 4 && std::memcmp(buf, "RTPS", 4) == 0) ++n;
    }
  }

 private:
  int fd_;
};

std::uint32_t group_port() {
  return PortPlan::data_multicast_port(static_cast<std::uint32_t>(test::test_domain().domain()));
}

DdsOptions member(const char* name, bool multicast, std::uint64_t run = kRun) {
  DdsOptions o = test::dds_options(name, run);
  if (multicast) o.state.multicast_group = state_multicast_group(run);
  return o;
}

// Publishes from `from` (of run `run`) until both others have heard it, then counts what
// run kRun's group carried while it sent 50 more samples.
int datagrams_to_the_group(bool multicast, std::uint64_t run = kRun) {
  GroupListener group(state_multicast_group(kRun).c_str(), group_port());
  DdsBus from(member("from", multicast, run));
  DdsBus a(member("a", multicast, run));
  DdsBus b(member("b", multicast, run));
  EXPECT_EQ(a.state().multicast_group(), multicast ? state_multicast_group(run) : "");
  std::uint64_t seq = 0;
  EXPECT_TRUE(test::wait_for(
      [&] {
        from.publish(test::state_sample(1, run, ++seq));
        return a.latest(0).size() == 1 && b.latest(0).size() == 1;
      },
      30.0));
  group.drain();
  const std::uint64_t before = a.counters().received + b.counters().received;
  for (int i = 0; i < 50; ++i) from.publish(test::state_sample(1, run, ++seq));
  const int sent = group.drain();
  // Every sample reached both readers: loopback loses none of these 100. (A sample or two of the
  // discovery loop above may still have been in flight when `before` was read.)
  EXPECT_TRUE(test::wait_for(
      [&] { return a.counters().received + b.counters().received >= before + 100; }, 10.0));
  EXPECT_LE(a.counters().received + b.counters().received, before + 104);
  return sent;
}

TEST(StateMulticast, OneDatagramPerSampleReachesEveryReaderThroughTheGroup) {
  const int sent = datagrams_to_the_group(true);
  // One datagram per sample, not one per reader; a few more may carry discovery's heartbeats.
  EXPECT_GE(sent, 45);
  EXPECT_LE(sent, 60);
}

TEST(StateMulticast, WithoutTheGroupNothingIsSentThere) {
  EXPECT_EQ(datagrams_to_the_group(false), 0);
}

TEST(StateMulticast, AnotherRunOnTheDomainSendsToItsOwnGroupWhichThisRunsSocketsNeverSee) {
  ASSERT_NE(state_multicast_group(kRun + 1), state_multicast_group(kRun));
  EXPECT_EQ(datagrams_to_the_group(true, kRun + 1), 0);
}

TEST(StateMulticast, APortHeldAloneByAnotherProgramLeavesTheReadersOnUnicastStillHearing) {
  // A socket bound to the port without sharing it: Fast DDS could not bind the group's socket.
  const int blocker = ::socket(AF_INET, SOCK_DGRAM, 0);
  ASSERT_GE(blocker, 0);
  sockaddr_in at{};
  at.sin_family = AF_INET;
  at.sin_port = htons(static_cast<std::uint16_t>(group_port()));
  at.sin_addr.s_addr = htonl(INADDR_ANY);
  ASSERT_EQ(::bind(blocker, reinterpret_cast<sockaddr*>(&at), sizeof at), 0)
      << std::strerror(errno);
  EXPECT_NE(multicast_port_problem(state_multicast_group(kRun), group_port(), "127.0.0.1"), "");
  {
    DdsBus from(member("from", true));
    DdsBus a(member("a", true));
    EXPECT_EQ(a.state().multicast_group(), "");
    std::uint64_t seq = 0;
    EXPECT_TRUE(test::wait_for(
        [&] {
          from.publish(test::state_sample(1, kRun, ++seq));
          return a.latest(0).size() == 1;
        },
        30.0));
  }
  ::close(blocker);
  EXPECT_EQ(multicast_port_problem(state_multicast_group(kRun), group_port(), "127.0.0.1"), "");
}

TEST(StateMulticast, EachRunHasItsOwnGroupOutsideDiscoverysOwn) {
  std::set<std::string> groups;
  for (std::uint64_t run = 0; run < 1000; ++run) {
    const std::string g = state_multicast_group(run);
    EXPECT_EQ(g, state_multicast_group(run));
    EXPECT_EQ(g.rfind("239.255.", 0), 0u) << g;
    EXPECT_NE(g.rfind("239.255.0.", 0), 0u) << g;
    EXPECT_NE(g.substr(g.size() - 2), ".0") << g;
    EXPECT_NE(g.substr(g.size() - 4), ".255") << g;
    groups.insert(g);
  }
  EXPECT_GT(groups.size(), 950u);  // 64 516 groups: few of 1000 runs share one
}

TEST(StateMulticast, TheLastReaderLeftStillHearsAndTheWriterLives) {
  // Readers matched one after the other, then all but the last one gone: the writer keeps
  // reaching it through the group (it has no unicast locator to fall back to).
  DdsBus from(member("from", false));  // so that the last reader is alone in the group
  std::vector<std::unique_ptr<DdsBus>> readers;
  std::uint64_t seq = 0;
  for (const char* name : {"first", "second", "last"}) {
    readers.push_back(std::make_unique<DdsBus>(member(name, true)));
    DdsBus& r = *readers.back();
    ASSERT_TRUE(test::wait_for(
        [&] {
          from.publish(test::state_sample(1, kRun, ++seq));
          return r.latest(0).size() == 1;
        },
        30.0))
        << name;
  }
  // Its writer is matched with the three and with its own participant's reader (in-process
  // delivery is off in these tests); hearing a sample does not mean every match is counted yet.
  ASSERT_TRUE(test::wait_for([&] { return from.matched_readers() == 4; }, 30.0));
  readers.erase(readers.begin(), readers.begin() + 2);
  ASSERT_TRUE(test::wait_for([&] { return from.matched_readers() == 2; }, 30.0));
  DdsBus& last = *readers.back();
  const std::uint64_t before = last.counters().received;
  EXPECT_TRUE(test::wait_for(
      [&] {
        from.publish(test::state_sample(1, kRun, ++seq));
        return last.counters().received >= before + 20;
      },
      30.0));
}

TEST(StateMulticast, ABadGroupIsRefusedNamingIt) {
  DdsOptions o = member("bad", true);
  o.state.multicast_group = "10.0.0.1";
  try {
    DdsBus bus(o);
    FAIL() << "a unicast address was taken as the group";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("10.0.0.1"), std::string::npos) << e.what();
  }
}

// A process's participant and bus settings as its flags plan them (load_for_process's replan).
DdsOptions planned(RunConfig rc, const ProcessOptions& po) {
  replan(rc, hosts_of(rc, po));
  return dds_options(rc, "agent", po);
}

// Which runs use the group: those where everyone hears everyone on loopback, and no others.
TEST(StateMulticast, OnlyAllToAllRunsOnLoopbackWithoutTheTestTransportOrUnicastDiscoveryUseIt) {
  RunConfig rc =
      resolve_scenario(parse_scenario_text("random_agents { count: 4 box_m: 10 } seed: 1", "test"));
  ASSERT_EQ(rc.plan.delivery, Delivery::kAll);
  const auto group = [](const RunConfig& r, ProcessOptions po = {}) {
    return planned(r, po).state.multicast_group;
  };
  EXPECT_EQ(group(rc), state_multicast_group(rc.transport.run_id));
  ProcessOptions server;  // discovery is not data: through a Discovery Server too
  server.discovery_server = "127.0.0.1:11811";
  EXPECT_EQ(group(rc, server), state_multicast_group(rc.transport.run_id));
  RunConfig neighbours = rc;
  neighbours.transport.delivery = Delivery::kNeighbours;
  EXPECT_EQ(group(neighbours), "");
  RunConfig lossy = rc;
  lossy.faults.transport_drop_percent = 20;
  EXPECT_EQ(group(lossy), "");
  ProcessOptions unicast;
  unicast.unicast_peers = "0:5";
  EXPECT_EQ(group(rc, unicast), "");
  RunConfig secure = rc;
  secure.transport.keystore = "/nonexistent/keystore";
  EXPECT_EQ(group(secure), "");
  RunConfig shm = rc;
  shm.transport.shared_memory = true;
  EXPECT_EQ(group(shm), "");
  ProcessOptions container;
  container.interface = "any";
  EXPECT_EQ(group(rc, container), "");
  ProcessOptions lan;
  lan.interface = "10.1.2.3";
  EXPECT_EQ(group(rc, lan), "");
  // A scenario can turn it off (a loopback without multicast), and the run's scenario.txtpb says
  // so.
  const RunConfig off = resolve_scenario(parse_scenario_text(
      "random_agents { count: 4 box_m: 10 } seed: 1 transport { multicast: false }", "test"));
  EXPECT_EQ(group(off), "");
  EXPECT_NE(to_text(off.resolved).find("multicast: false"), std::string::npos);
  EXPECT_NE(to_text(rc.resolved).find("multicast: true"), std::string::npos);
}

// Cells become region topics only through a Discovery Server and past 128 agents, where one
// shared topic would have the server introduce everyone to everyone.
TEST(RegionTopics, OnlyThroughADiscoveryServerAndPastOneHundredTwentyEightAgents) {
  const auto regions = [](int agents, const std::string& server) {
    const RunConfig rc = resolve_scenario(parse_scenario_text(
        "random_agents { count: " + std::to_string(agents) + " box_m: 100 } seed: 1", "test"));
    ProcessOptions po;
    po.discovery_server = server;
    const DdsOptions d = planned(rc, po);
    EXPECT_EQ(d.state.routing != Routing::kPartitions, !server.empty());
    return d.state.routing == Routing::kRegionTopics;
  };
  EXPECT_FALSE(regions(128, "127.0.0.1:11811"));
  EXPECT_TRUE(regions(129, "127.0.0.1:11811"));
  EXPECT_TRUE(regions(256, "127.0.0.1:11811"));
  EXPECT_FALSE(regions(256, ""));
}

// --peer-hosts: one participant per host (a container), so id 0 of the port plan and the peers
// 0:1 at each host, unless told otherwise; never the multicast group.
TEST(PeerHosts, MeanOneParticipantPerHostUnlessTold) {
  RunConfig rc =
      resolve_scenario(parse_scenario_text("random_agents { count: 4 box_m: 10 } seed: 1", "test"));
  ProcessOptions po;
  po.interface = "any";
  po.peer_hosts = "agent,supervisor";
  DdsOptions d = planned(rc, po);
  EXPECT_EQ(d.participant.participant_id, 0);
  EXPECT_EQ(d.participant.unicast_peers_first, 0);
  EXPECT_EQ(d.participant.unicast_peers_count, 1);
  EXPECT_EQ(d.state.multicast_group, "");
  po.participant_id = 7;
  po.unicast_peers = "5:3";
  d = planned(rc, po);
  EXPECT_EQ(d.participant.participant_id, 7);
  EXPECT_EQ(d.participant.unicast_peers_first, 5);
  EXPECT_EQ(d.participant.unicast_peers_count, 3);
}

// The names' addresses, each once; fewer than wanted after the wait: what was found, said once.
TEST(PeerHosts, AreEveryAddressOfTheNamesEachOnceAndTooFewAreSaid) {
  std::vector<std::string> said;
  const auto say = [&](const std::string& line) { said.push_back(line); };
  const std::atomic<bool> go{false};
  EXPECT_EQ(find_peer_hosts("127.0.0.1,localhost,127.0.0.1", 1, 0.0, go, say),
            std::vector<std::string>{"127.0.0.1"});
  ASSERT_EQ(said.size(), 1u);
  EXPECT_NE(said[0].find("1 addresses after 0 s: discovery by unicast"), std::string::npos)
      << said[0];
  said.clear();
  EXPECT_EQ(find_peer_hosts("127.0.0.1,127.0.0.2", 3, 0.0, go, say),
            (std::vector<std::string>{"127.0.0.1", "127.0.0.2"}));
  ASSERT_EQ(said.size(), 1u);
  EXPECT_NE(said[0].find("2 of 3 addresses"), std::string::npos) << said[0];
  EXPECT_NE(said[0].find("going on"), std::string::npos) << said[0];
  // A signal while it waits: at once, with what it has (a minute's wait asked for).
  const std::atomic<bool> stopped{true};
  EXPECT_EQ(find_peer_hosts("127.0.0.1", 3, 60.0, stopped, say),
            std::vector<std::string>{"127.0.0.1"});
}

}  // namespace
}  // namespace qswarm
