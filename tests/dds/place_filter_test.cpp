// An agent that hears by place (Interest::near) takes only the samples of agents within its reach:
// its readers' roster filter judges each sample on arrival by the place kept in its process (no
// writer judges for its readers), follows it as it moves without discovery, and still passes
// what it hears by name or by a bond.
#include <gtest/gtest.h>

#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "common/dds/dds_bus.hpp"
#include "common/dds/idl_convert.hpp"
#include "common/dds/roster_filter.hpp"
#include "common/transport/interest.hpp"
#include "tests/dds/test_bus.hpp"
#include "tests/swarm/harness.hpp"

#include "swarm_statePubSubTypes.h"

namespace qswarm {
namespace {

constexpr std::uint64_t kRun = 0x90;

// Agent 1 listens at the origin; agent 2 flies 100 m away, agent 3 1 m away. All share one cell
// (as a dense swarm does), so only the place filter tells them apart.
struct Three {
  std::vector<std::unique_ptr<DdsBus>> agents;
  std::vector<Vec3> at{Vec3(0, 0, 0), Vec3(100, 0, 0), Vec3(1, 0, 0)};
  std::uint64_t seq = 0;

  // kNamedTopics: agent names are topics of their own (as for a Discovery Server's clients).
  explicit Three(Routing routing = Routing::kPartitions) {
    for (AgentId a = 1; a <= 3; ++a) {
      DdsOptions o = test::dds_options(("agent-" + std::to_string(a)).c_str(), kRun);
      o.state.self = a;
      o.state.roster = {1, 2, 3};
      o.state.routing = routing;
      agents.push_back(std::make_unique<DdsBus>(o));
    }
    for (AgentId a = 1; a <= 3; ++a) listen_at(a, at[a - 1], {});
  }
  DdsBus& agent(AgentId a) { return *agents.at(a - 1); }
  std::vector<std::vector<AgentId>> links{{}, {}, {}};  // what each agent's samples say it links
  // Agent a hears the cell "c" within 5 m of a box of 1 m about `centre`, and these agents by
  // name.
  void listen_at(AgentId a, const Vec3& centre, std::vector<std::string> names) {
    Interest in;
    in.publish = {agent_partition(a), "c"};
    names.emplace_back("c");
    std::sort(names.begin(), names.end());
    in.subscribe = names;
    in.near = {Reach{'p', centre - Vec3::Constant(0.5), centre + Vec3::Constant(0.5), 5.0}};
    agent(a).set_interest(in);
  }
  void publish() {
    ++seq;
    for (AgentId a = 1; a <= 3; ++a) {
      StateMessage m = test::state_sample(a, kRun, seq);
      m.p_W = at[a - 1];
      m.view.q = at[a - 1];
      for (const AgentId peer : links[a - 1]) m.links.emplace_back(peer, 1.0);
      agent(a).publish(m);
    }
  }
  std::uint64_t seq_heard(AgentId by, AgentId from) {
    for (const StateMessage& m : agent(by).latest(by))
      if (m.view.id == from) return m.seq;
    return 0;
  }
  std::uint64_t judged(AgentId a) { return agent(a).state().judged_on_arrival(); }
  // Every agent publishes, round after round, until `heard` holds (at most 30 s).
  bool publish_until(const std::function<bool()>& heard) {
    return test::wait_for(
        [&] {
          publish();
          return heard();
        },
        30.0);
  }
};

TEST(PlaceFilter, AReaderTakesOnlyTheSendersWithinItsReachWhereverItMoves) {
  Three s;
  ASSERT_TRUE(s.publish_until([&] { return s.seq_heard(1, 3) > 10 && s.seq_heard(3, 1) > 10; }));
  // Every sample reaches agent 1's reader and is judged there: agent 2's, 100 m away, are dropped.
  const std::uint64_t judged = s.judged(1), from = s.seq;
  ASSERT_TRUE(s.publish_until([&] { return s.seq_heard(1, 3) >= from + 50; }));
  EXPECT_EQ(s.seq_heard(1, 2), 0u);
  EXPECT_GE(s.judged(1), judged + 50);

  // Agent 1 moves next to agent 2: it hears agent 2 and no longer agent 3.
  s.listen_at(1, Vec3(99, 0, 0), {});
  ASSERT_TRUE(s.publish_until([&] { return s.seq_heard(1, 2) > 0; }));
  const std::uint64_t moved = s.seq;
  ASSERT_TRUE(s.publish_until([&] { return s.seq_heard(1, 2) >= moved + 20; }));
  EXPECT_LT(s.seq_heard(1, 3), moved + 20);

  // An agent heard by name is heard wherever it is.
  s.listen_at(1, Vec3(0, 0, 0), {agent_partition(2)});
  const std::uint64_t named = s.seq;
  ASSERT_TRUE(s.publish_until(
      [&] { return s.seq_heard(1, 2) >= named + 20 && s.seq_heard(1, 3) >= named + 20; }));

  // A bond (a link, an exchange being settled) passes whatever the place: once agent 3's samples
  // name agent 2, 99 m away, as a link, agent 2's reader takes them. A bond is the sender's:
  // agent 3 still does not hear agent 2, whose samples do not name it.
  EXPECT_EQ(s.seq_heard(2, 3), 0u);
  const std::uint64_t before = s.seq;
  s.links[2] = {2};
  ASSERT_TRUE(s.publish_until([&] { return s.seq_heard(2, 3) >= before + 20; }));
  EXPECT_EQ(s.seq_heard(3, 2), 0u);
}

// An agent's name is a topic of its own: what arrives on it passes wherever its sender is, as on
// the shared topic.
TEST(PlaceFilter, AnAgentHeardByNameOnATopicOfItsOwnIsHeardWhereverItIs) {
  Three s(Routing::kNamedTopics);
  ASSERT_TRUE(s.publish_until([&] { return s.seq_heard(1, 3) > 10; }));
  const std::uint64_t from = s.seq;
  ASSERT_TRUE(s.publish_until([&] { return s.seq_heard(1, 3) >= from + 50; }));
  EXPECT_EQ(s.seq_heard(1, 2), 0u);  // 100 m away, and not heard by name

  s.listen_at(1, Vec3(0, 0, 0), {agent_partition(2)});
  const std::uint64_t named = s.seq;
  ASSERT_TRUE(s.publish_until(
      [&] { return s.seq_heard(1, 2) >= named + 20 && s.seq_heard(1, 3) >= named + 20; }));
}

// The filter finds the agents a serialized sample names (its links, flows, copies, asking) where
// the generated type puts them, whatever else the sample carries: the same answer as mentions()
// on the decoded sample, for seeded random samples.
TEST(PlaceFilter, ASerializedSampleNamesTheAgentsItsDecodedSampleNames) {
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<int> count(0, 5), peer(1, 12), small(0, 16);
  const auto entries = [&] {
    std::vector<FlowEntry> v(static_cast<std::size_t>(count(rng)));
    for (FlowEntry& e : v) e = {static_cast<AgentId>(peer(rng)), Vec3(1, 2, 3), 0.5, true};
    return v;
  };
  int named = 0;
  for (int k = 0; k < 500; ++k) {
    StateMessage m;
    m.view.id = 99;
    for (int i = count(rng); i > 0; --i) m.links.emplace_back(peer(rng), 1.5);
    for (int i = count(rng); i > 0; --i) m.initial_links.emplace_back(peer(rng), 1.5);
    m.view.flows = entries();
    m.view.copies = entries();
    for (int i = count(rng); i > 0; --i) m.view.asking.push_back(static_cast<AgentId>(peer(rng)));
    for (int i = small(rng); i > 0; --i) m.strangers.push_back(static_cast<AgentId>(1000 + i));
    for (int i = small(rng); i > 0; --i) m.suspects.push_back({static_cast<AgentId>(i), 3});
    qswarm_msgs::AgentState s;
    to_idl(m, s);
    qswarm_msgs::AgentStatePubSubType type;
    eprosima::fastrtps::rtps::SerializedPayload_t payload(type.m_typeSize);
    ASSERT_TRUE(type.serialize(&s, &payload));
    for (AgentId id = 1; id <= 12; ++id) {
      ASSERT_EQ(serialized_mentions(payload.data, payload.length, id), mentions(m, id))
          << "sample " << k << ", agent " << id;
      named += mentions(m, id);
      // Cut short, it names nobody (and nothing beyond its end is read).
      EXPECT_FALSE(serialized_mentions(payload.data, payload.length / 2, id));
    }
  }
  EXPECT_GT(named, 1000);  // the property was tested, not skipped
  EXPECT_FALSE(serialized_mentions(nullptr, 0, 1));
}

TEST(PlaceFilter, AReachHoldsPointsWithinItsRadiusOfTheBox) {
  const Reach r{'p', Vec3(0, 0, 0), Vec3(1, 1, 1), 2.0};
  EXPECT_TRUE(r.contains(Vec3(0.5, 0.5, 0.5)));
  EXPECT_TRUE(r.contains(Vec3(3.0, 1.0, 1.0)));
  EXPECT_FALSE(r.contains(Vec3(3.0 + 1e-9, 1.0, 1.0)));
  EXPECT_TRUE(r.contains(Vec3(-1.4, -1.4, 0.5)));
  EXPECT_FALSE(r.contains(Vec3(-1.5, -1.5, 0.5)));
  EXPECT_FALSE(r.contains(Vec3(std::nan(""), 0, 0)));
  EXPECT_FALSE(r.contains(Vec3(HUGE_VAL, 0, 0)));
}

}  // namespace
}  // namespace qswarm
