// Through a Discovery Server, an agent whose interest names are topics (Routing::kNamedTopics)
// discovers only the participants it shares a name with, and meets a new one when its interest
// grows; with names as partitions of one topic (the control) every participant discovers every
// other.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <fastdds/dds/topic/Topic.hpp>

#include "common/dds/dds_bus.hpp"
#include "common/dds/discovery_server.hpp"
#include "common/transport/interest.hpp"
#include "common/transport/port_plan.hpp"
#include "tests/dds/test_bus.hpp"
#include "tests/swarm/domain_lease.hpp"
#include "tests/swarm/harness.hpp"

#include "swarm_statePubSubTypes.h"

namespace qswarm {
namespace {

constexpr std::uint64_t kRun = 0x70;

struct Swarm {
  std::unique_ptr<DiscoveryServer> server;
  std::vector<std::unique_ptr<DdsBus>> agents;  // agents 1 to 4
  std::uint64_t seq = 0;

  explicit Swarm(Routing routing, bool pairs = true) {
    const auto domain = static_cast<std::uint32_t>(test::test_domain().domain());
    const std::optional<int> id = free_participant_block(domain, 1, "127.0.0.1");
    if (!id) throw std::runtime_error("no free participant id on the test's domain");
    const auto port = static_cast<std::uint16_t>(PortPlan::discovery_port(domain, *id));
    server = std::make_unique<DiscoveryServer>(domain, "127.0.0.1", port, *id);
    for (AgentId a = 1; a <= 4; ++a) {
      DdsOptions o = test::dds_options(("agent-" + std::to_string(a)).c_str(), kRun);
      o.participant.discovery_server = "127.0.0.1:" + std::to_string(port);
      o.state.routing = routing;
      o.state.self = a;
      o.state.roster = {1, 2, 3, 4};
      agents.push_back(std::make_unique<DdsBus>(o));
    }
    if (!pairs) return;
    // Two pairs: 1 and 2 hear each other by name, 3 and 4 share a cell.
    agent(1).set_interest({{"a1"}, {"a2"}, {}});
    agent(2).set_interest({{"a2"}, {"a1"}, {}});
    agent(3).set_interest({{"a3", "c.0.0.0"}, {"c.0.0.0"}, {}});
    agent(4).set_interest({{"a4", "c.0.0.0"}, {"c.0.0.0"}, {}});
  }
  DdsBus& agent(AgentId a) { return *agents.at(a - 1); }
  int known(AgentId a) { return agent(a).participant().writers().participants_known(); }
  // The sequence number of the last sample of `from` that `by` heard (0: none).
  std::uint64_t seq_heard(AgentId by, AgentId from) {
    for (const StateMessage& m : agent(by).latest(by))
      if (m.view.id == from) return m.seq;
    return 0;
  }
  bool heard(AgentId by, AgentId from) { return seq_heard(by, from) > 0; }
  // Publishes until agents 1 and 2, and 3 and 4, hear each other (false: not within 30 s).
  bool pairs_meet() {
    return test::wait_for(
        [&] {
          publish();
          return heard(1, 2) && heard(2, 1) && heard(3, 4) && heard(4, 3);
        },
        30.0);
  }
  void publish() {
    ++seq;
    for (AgentId a = 1; a <= 4; ++a) agent(a).publish(test::state_sample(a, kRun, seq));
  }
  ~Swarm() {
    agents.clear();  // the clients before their server
    server.reset();
  }
};

// Fast DDS 2.9.1 aborts a server whose timed announcement goes to a client it has not opened an
// output channel for yet (discovery_server.cpp): the server never announces on a timer, and its
// clients still meet it and, through it, each other.
TEST(NeighbourTopics, TheDiscoveryServerNeverAnnouncesOnATimerAndItsClientsStillMeet) {
  Swarm s(Routing::kNamedTopics);
  const DiscoveryServer::Announcements own = s.server->announcements();
  EXPECT_EQ(own.initial, 0u);
  EXPECT_GE(own.period_s, 30.0 * 24 * 3600);
  ASSERT_TRUE(s.pairs_meet());
  for (AgentId a = 1; a <= 4; ++a) EXPECT_EQ(s.known(a), 2) << "agent " << a;
}

// The local addresses of this process's UDP sockets, by socket inode (/proc/self/net/udp).
std::map<std::string, std::string> own_udp_sockets() {
  std::set<std::string> inodes;
  for (const auto& fd : std::filesystem::directory_iterator("/proc/self/fd")) {
    std::error_code ec;
    const std::string target = std::filesystem::read_symlink(fd.path(), ec).string();
    if (!ec && target.rfind("socket:[", 0) == 0) inodes.insert(target.substr(8, target.size() - 9));
  }
  std::map<std::string, std::string> out;
  std::ifstream udp("/proc/self/net/udp");
  std::string line;
  std::getline(udp, line);  // the header
  while (std::getline(udp, line)) {
    std::istringstream in(line);
    std::string slot, local, remote, state, queues, timer, retr, uid, timeout, inode;
    in >> slot >> local >> remote >> state >> queues >> timer >> retr >> uid >> timeout >> inode;
    if (!inodes.count(inode)) continue;
    // The kernel prints the address as the hex of its network-order word read in host order.
    in_addr a{};
    a.s_addr = static_cast<std::uint32_t>(std::stoul(local.substr(0, 8), nullptr, 16));
    char text[INET_ADDRSTRLEN] = {};
    ::inet_ntop(AF_INET, &a, text, sizeof text);
    out[inode] = text;
  }
  return out;
}

TEST(NeighbourTopics, ADiscoveryServerOnLoopbackHasNoSocketOnAnyOtherAddress) {
  // Given a server listening on 127.0.0.1
  const std::map<std::string, std::string> before = own_udp_sockets();
  const auto domain = static_cast<std::uint32_t>(test::test_domain().domain());
  const std::optional<int> id = free_participant_block(domain, 1, "127.0.0.1");
  ASSERT_TRUE(id);
  DiscoveryServer server(domain, "127.0.0.1",
                         static_cast<std::uint16_t>(PortPlan::discovery_port(domain, *id)), *id);
  // Then each socket it opened is bound to loopback: none to 0.0.0.0, none to another interface
  int opened = 0;
  for (const auto& [inode, address] : own_udp_sockets()) {
    if (before.count(inode)) continue;
    ++opened;
    EXPECT_EQ(address, "127.0.0.1") << "socket " << inode;
  }
  EXPECT_GE(opened, 2);  // its discovery socket and its default unicast one, at least
}

TEST(NeighbourTopics, ThroughADiscoveryServerAnAgentDiscoversOnlyThoseItSharesANameWith) {
  Swarm s(Routing::kNamedTopics);
  ASSERT_TRUE(s.pairs_meet());
  // Each knows its partner and the server, and was sent nothing of the other pair.
  for (AgentId a = 1; a <= 4; ++a) EXPECT_EQ(s.known(a), 2) << "agent " << a;
  EXPECT_FALSE(s.heard(1, 3) || s.heard(1, 4) || s.heard(3, 1) || s.heard(3, 2));
  EXPECT_EQ(s.agent(1).matched_readers(), 1);

  // Agent 3 starts listening to agent 1 by name: the server introduces them, samples flow.
  s.agent(3).set_interest({{"a3", "c.0.0.0"}, {"a1", "c.0.0.0"}, {}});
  ASSERT_TRUE(test::wait_for(
      [&] {
        s.publish();
        return s.heard(3, 1) && s.agent(1).matched_readers() == 2;
      },
      30.0));
  EXPECT_EQ(s.known(1), 3);
  EXPECT_EQ(s.known(3), 3);
  EXPECT_EQ(s.known(2), 2);  // agent 2 still knows only agent 1 and the server
  EXPECT_EQ(s.known(4), 2);

  // And stops: its reader goes, agent 1 sends to one reader again.
  s.agent(3).set_interest({{"a3", "c.0.0.0"}, {"c.0.0.0"}, {}});
  ASSERT_TRUE(test::wait_for(
      [&] {
        s.publish();
        return s.agent(1).matched_readers() == 1;
      },
      30.0));
  // Nothing of agent 1 reaches agent 3 any more, while agent 4 still does.
  const std::uint64_t stopped = s.seq;
  ASSERT_TRUE(test::wait_for(
      [&] {
        s.publish();
        return s.seq_heard(3, 4) >= stopped + 20;
      },
      30.0));
  EXPECT_LE(s.seq_heard(3, 1), stopped);
}

// Agent `id` in the cell "p<x>.0.0", listening to the cells about it as Neighbourhood does.
Interest in_cell(AgentId id, int x) {
  const std::string cell = "p" + std::to_string(x) + ".0.0";
  Interest in;
  in.publish = {agent_partition(id), cell};
  in.subscribe = cells_about(cell, 2);
  std::sort(in.publish.begin(), in.publish.end());
  std::sort(in.subscribe.begin(), in.subscribe.end());
  return in;
}

// Cells are partitions of their region's topic (regions of kRegionCells = 5 cells: x 0..4 is
// one, 5..9 the next): agents discover the agents of the regions about them, and one moving
// into another region is heard there at once, through a writer its new listeners matched while
// it was a cell away.
TEST(NeighbourTopics, CellsArePartitionsOfRegionTopicsAndAMoveAcrossNeedsNoDiscovery) {
  Swarm s(Routing::kRegionTopics, /*pairs=*/false);
  s.agent(1).set_interest(in_cell(1, 4));  // the mover, at the edge of region 0
  s.agent(2).set_interest(in_cell(2, 2));  // listens to x 0..4: region 0 alone
  s.agent(3).set_interest(in_cell(3, 7));  // listens to x 5..9: region 1 alone
  s.agent(4).set_interest(in_cell(4, 8));
  ASSERT_TRUE(test::wait_for(
      [&] {
        s.publish();
        return s.heard(2, 1) && s.heard(1, 2) && s.heard(3, 4) && s.heard(4, 3) && s.known(3) == 3;
      },
      30.0));
  // Agent 3 knows the mover (an idle writer of it on region 1 matched its reader) but hears
  // nothing from it; agent 2 shares no region with 3 and 4 and never meets them.
  // The mover's idle writer on region 1's topic rp1.0.0 (cells p5.0..1.0..1) matched with its
  // own reader and agent 3's, not agent 4's (whose cells begin at x = 6).
  const std::uint64_t before = s.seq;
  ASSERT_TRUE(test::wait_for(
      [&] {
        s.publish();
        return s.seq_heard(3, 4) >= before + 20 &&
               s.agent(1).state().region_readers_matched("rp1.0.0") == 2;
      },
      30.0));
  EXPECT_FALSE(s.heard(3, 1));
  EXPECT_EQ(s.known(2), 2);                    // the mover and the server
  EXPECT_EQ(s.agent(1).matched_readers(), 2);  // its own reader and agent 2's hear its cell

  // Into region 1: the idle writer becomes the one written, already matched with agent 3's
  // reader (no discovery round: a new writer would have matched only its own reader yet), and
  // agent 2 no longer hears the mover (nor does agent 4, whose cells begin at x = 6).
  s.agent(1).set_interest(in_cell(1, 5));
  const std::uint64_t moved = s.seq;
  EXPECT_EQ(s.agent(1).matched_readers(), 2);  // its own and agent 3's
  ASSERT_TRUE(test::wait_for(
      [&] {
        s.publish();
        return s.heard(3, 1);
      },
      30.0));
  ASSERT_TRUE(test::wait_for(
      [&] {
        s.publish();
        return s.seq_heard(3, 1) >= moved + 20;
      },
      30.0));
  EXPECT_LE(s.seq_heard(2, 1), moved);
  EXPECT_FALSE(s.heard(4, 1));
  EXPECT_EQ(s.known(2), 2);
}

// Cells of two spaces (proximity and collision avoidance) stay partitions of the shared topic: as
// regions, each sample would go out once per space, and a listener of both would hear it twice.
TEST(NeighbourTopics, CellsOfTwoSpacesStayOnTheSharedTopic) {
  Swarm s(Routing::kRegionTopics, /*pairs=*/false);
  for (AgentId a = 1; a <= 2; ++a) {
    Interest in = in_cell(a, 0);
    const std::vector<std::string> q = cells_about("q0.0.0", 2);
    in.publish.push_back("q0.0.0");
    in.subscribe.insert(in.subscribe.end(), q.begin(), q.end());
    std::sort(in.publish.begin(), in.publish.end());
    std::sort(in.subscribe.begin(), in.subscribe.end());
    s.agent(a).set_interest(in);
  }
  ASSERT_TRUE(test::wait_for(
      [&] {
        s.publish();
        return s.heard(1, 2) && s.heard(2, 1) && s.agent(1).matched_readers() == 2;
      },
      30.0));
  EXPECT_EQ(s.agent(1).state().region_readers_matched("rp0.0.0"), 0);
  EXPECT_EQ(s.agent(1).state().region_readers_matched("rq0.0.0"), 0);
}

// The control: the same interests as partitions of one topic. The server relays every participant
// to every other, whatever the partitions (DDS matches partitions after discovery).
TEST(NeighbourTopics, AsPartitionsOfOneTopicEveryAgentDiscoversEveryOther) {
  Swarm s(Routing::kPartitions);
  ASSERT_TRUE(test::wait_for(
      [&] {
        s.publish();
        bool all = s.heard(1, 2) && s.heard(2, 1) && s.heard(3, 4) && s.heard(4, 3);
        for (AgentId a = 1; a <= 4; ++a) all = all && s.known(a) == 4;
        return all;
      },
      30.0));
  EXPECT_FALSE(s.heard(1, 3) || s.heard(1, 4));  // the partitions still keep the pairs apart
}

namespace dds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastrtps::rtps;

// What a participant hears through discovery of one other participant's state readers: how often
// each was updated, and which topics' readers it has discovered.
class ReaderUpdates final : public dds::DomainParticipantListener {
 public:
  explicit ReaderUpdates(const rtps::GuidPrefix_t& of) : of_(of) {}
  void on_subscriber_discovery(dds::DomainParticipant*, rtps::ReaderDiscoveryInfo&& info) override {
    if (info.info.guid().guidPrefix != of_) return;
    std::lock_guard<std::mutex> lock(mu_);
    if (info.status == rtps::ReaderDiscoveryInfo::CHANGED_QOS_READER) ++updates_[info.info.guid()];
    if (info.status == rtps::ReaderDiscoveryInfo::DISCOVERED_READER)
      topics_.insert(info.info.topicName().to_string());
  }
  bool discovered(const std::string& topic) const {
    std::lock_guard<std::mutex> lock(mu_);
    return topics_.count(topic) > 0;
  }
  std::map<rtps::GUID_t, int> take_updates() {
    std::lock_guard<std::mutex> lock(mu_);
    return std::exchange(updates_, {});
  }

 private:
  const rtps::GuidPrefix_t of_;
  mutable std::mutex mu_;
  std::map<rtps::GUID_t, int> updates_;
  std::set<std::string> topics_;
};

// How often a move (another cell, another place; or only another place) updates each state
// reader of the agent that moves, as its peers hear through discovery. Fast DDS 2.9.1's Discovery
// Server corrupts its history when two updates of one reader reach it together
// (docs/fast-dds-workarounds.md, W5), as a change of the readers' partitions
// followed by one of their filter parameters did. Simple discovery here: an observer hears every
// update itself.
std::vector<int> updates_per_reader(bool region_topics, int to_x, double near_x) {
  DdsOptions o = test::dds_options("mover", kRun);
  o.state.self = 1;
  o.state.roster = {1, 2};
  o.state.routing = region_topics ? Routing::kRegionTopics : Routing::kPartitions;
  DdsBus mover(o);
  dds::DomainParticipant* p = mover.participant().get();
  ReaderUpdates updates(p->guid().guidPrefix);
  DdsParticipant observer(test::dds_options("observer", kRun).participant);
  observer.get()->set_listener(&updates);

  // A marker: the readers a participant announces reach a peer in order, so once the observer
  // has discovered a marker reader, it has heard of everything announced before it. (Left behind
  // by a throw, the markers go with the participant's contained entities.)
  dds::Subscriber* sub = p->create_subscriber(dds::SUBSCRIBER_QOS_DEFAULT);
  std::vector<std::pair<dds::Topic*, dds::DataReader*>> markers;
  const auto heard_all = [&] {
    const std::string name = "qswarm/test/marker" + std::to_string(markers.size());
    dds::Topic* t = p->create_topic(name, qswarm_msgs::AgentStatePubSubType().getName(),
                                    dds::TOPIC_QOS_DEFAULT);
    markers.emplace_back(t, t ? sub->create_datareader(t, dds::DATAREADER_QOS_DEFAULT) : nullptr);
    return markers.back().second && test::wait_for([&] { return updates.discovered(name); }, 30.0);
  };

  Interest in = in_cell(1, 3);  // listens to x 1..5: regions 0 and 1 of x, y and z
  in.near = {Reach{'p', Vec3(15, 0, 0), Vec3(16, 1, 1), 5.0}};
  mover.set_interest(in);
  EXPECT_TRUE(heard_all());
  updates.take_updates();
  in = in_cell(1, to_x);
  in.near = {Reach{'p', Vec3(near_x, 0, 0), Vec3(near_x + 1, 1, 1), 5.0}};
  mover.set_interest(in);
  EXPECT_TRUE(heard_all());
  std::vector<int> out;
  for (const auto& [reader, n] : updates.take_updates()) out.push_back(n);

  observer.get()->set_listener(nullptr);
  for (auto& [t, r] : markers) {
    if (r) sub->delete_datareader(r);
    if (t) p->delete_topic(t);
  }
  p->delete_subscriber(sub);
  return out;
}

TEST(NeighbourTopics, AMoveUpdatesTheSharedTopicsReaderOnce) {
  EXPECT_EQ(updates_per_reader(/*region_topics=*/false, 4, 20.0), std::vector<int>{1});
}

// To x 2..6: the same 8 regions (x 0 and 1; y and z -1 and 0).
TEST(NeighbourTopics, AMoveUpdatesEachRegionReaderOnce) {
  EXPECT_EQ(updates_per_reader(/*region_topics=*/true, 4, 20.0), std::vector<int>(8, 1));
}

// To x 6..10: the readers of region x 0 go without an update, those of x 1 are updated once,
// those of x 2 come.
TEST(NeighbourTopics, AMoveAcrossRegionsUpdatesNoReaderThatGoes) {
  EXPECT_EQ(updates_per_reader(/*region_topics=*/true, 8, 40.0), std::vector<int>(4, 1));
}

// Where it hears by place changes every few ticks; the cells it listens to far less often.
TEST(NeighbourTopics, AnInterestThatKeepsItsCellsUpdatesNoReader) {
  EXPECT_EQ(updates_per_reader(/*region_topics=*/false, 3, 16.0), std::vector<int>{});
  EXPECT_EQ(updates_per_reader(/*region_topics=*/true, 3, 16.0), std::vector<int>{});
}

}  // namespace
}  // namespace qswarm
