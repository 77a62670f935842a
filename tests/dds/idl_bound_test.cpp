// No silent bounds on the wire: a state message carries every link, flow and copy of the largest
// swarm a scenario allows, and refuses (never cuts) more.
#include <gtest/gtest.h>

#include <cmath>

#include "common/dds/idl_convert.hpp"

namespace qswarm {
namespace {

StateMessage with_entries(std::size_t n) {
  StateMessage m;
  m.view.id = 1;
  for (std::size_t k = 0; k < n; ++k) {
    const auto peer = static_cast<AgentId>(k + 2);
    m.links.emplace_back(peer, 1.0);
    m.initial_links.emplace_back(peer, 1.0);
    m.view.flows.push_back({peer, Vec3(1, 2, 3) * static_cast<double>(k), 1.0, true});
    m.view.copies.push_back({peer, Vec3(3, 2, 1), 0.0, k % 2 == 0});
  }
  return m;
}

TEST(WireBound, TheLargestSwarmsFlowsAllSurviveTheRoundTrip) {
  const StateMessage m = with_entries(kMaxSwarmAgents - 1);
  qswarm_msgs::AgentState s;
  to_idl(m, s);
  const StateMessage back = from_idl(s);
  ASSERT_EQ(back.view.flows.size(), kMaxSwarmAgents - 1);
  ASSERT_EQ(back.view.copies.size(), kMaxSwarmAgents - 1);
  ASSERT_EQ(back.links.size(), kMaxSwarmAgents - 1);
  ASSERT_EQ(back.initial_links.size(), kMaxSwarmAgents - 1);
  EXPECT_EQ(back.view.flows.back().flow, m.view.flows.back().flow);
  EXPECT_EQ(back.view.flows.back().peer, m.view.flows.back().peer);
  // A copy's active (its holder links the owner) is what lets the owner move on the edge.
  for (std::size_t k = 0; k < 2; ++k) EXPECT_EQ(back.view.copies[k].active, k % 2 == 0);
}

TEST(WireBound, DecodingIntoAReusedMessageLeavesNothingOfTheOneBefore) {
  // The receive path decodes every sample into the same message: a small sample after a large
  // one, from another agent, must read exactly as if decoded fresh.
  StateMessage big = with_entries(40);
  big.strangers = {900, 901};
  big.suspects = {{7, 3}};
  big.view.asking = {3, 4};
  big.barrier_known = {1, 2, 3};
  big.barrier_ready = {1};
  big.barrier_ready_at_s = 12.5;
  big.host = "node-7/10.1.2.3";
  big.view.link_distance_m = 2.5;  // set by a receiver, never on the wire
  big.view.current = false;
  StateMessage small = with_entries(2);
  small.view.id = 9;
  small.seq = 77;
  small.p_W = Vec3(4, 5, 6);
  qswarm_msgs::AgentState wire_big;
  qswarm_msgs::AgentState wire_small;
  to_idl(big, wire_big);
  to_idl(small, wire_small);
  StateMessage reused;
  from_idl(wire_big, reused);
  reused.view.link_distance_m = 2.5;
  reused.view.current = false;
  from_idl(wire_small, reused);
  const StateMessage fresh = from_idl(wire_small);
  qswarm_msgs::AgentState again_reused;
  qswarm_msgs::AgentState again_fresh;
  to_idl(reused, again_reused);
  to_idl(fresh, again_fresh);
  EXPECT_TRUE(again_reused == again_fresh);
  EXPECT_TRUE(again_reused == wire_small);
  EXPECT_EQ(reused.view.link_distance_m, fresh.view.link_distance_m);
  EXPECT_EQ(reused.view.current, fresh.view.current);
  EXPECT_EQ(reused.view.flows.size(), 2u);
  EXPECT_TRUE(reused.strangers.empty());
  EXPECT_TRUE(reused.suspects.empty());
  EXPECT_TRUE(reused.barrier_known.empty());
  EXPECT_EQ(reused.barrier_ready_at_s, 0.0);
  EXPECT_EQ(reused.host, "");
}

TEST(WireBound, AHostIsCarriedUpToItsBoundAndANetworkOneThatIsNotPrintableIsRefused) {
  StateMessage m = with_entries(1);
  m.host = std::string(kMaxHostBytes - 9, 'n') + "/10.0.0.1";
  qswarm_msgs::AgentState s;
  to_idl(m, s);
  EXPECT_EQ(from_idl(s).host, m.host);
  EXPECT_EQ(check_message(m), "");
  m.host += "0";  // one byte over: refused, never cut
  EXPECT_THROW(to_idl(m, s), std::length_error);
  EXPECT_EQ(check_message(m), "host too long or not printable");
  // What a forger may put on the wire: a line break or a quote for events.csv, bytes that are
  // not text for the live view.
  for (const std::string& bad : {std::string("a\nb"), std::string("a,b"), std::string("a\"b"),
                                 std::string("a\377b"), std::string("a\0b", 3)}) {
    m.host = bad;
    EXPECT_EQ(check_message(m), "host too long or not printable") << bad;
  }
}

TEST(WireBound, TheStartBarriersBitsetsCoverTheLargestSwarm) {
  StateMessage m = with_entries(1);
  m.barrier_known.assign(kMaxBarrierBytes, 0xff);
  m.barrier_ready.assign(kMaxBarrierBytes, 0x0f);
  m.barrier_ready_at_s = 4321.25;
  qswarm_msgs::AgentState s;
  to_idl(m, s);
  const StateMessage back = from_idl(s);
  EXPECT_EQ(back.barrier_known, m.barrier_known);
  EXPECT_EQ(back.barrier_ready, m.barrier_ready);
  EXPECT_EQ(back.barrier_ready_at_s, 4321.25);
  EXPECT_EQ(check_message(back), "");
  // One byte more is refused, never cut; a receiver refuses such a sample and an absurd instant
  m.barrier_ready.push_back(0);
  EXPECT_THROW(to_idl(m, s), std::length_error);
  EXPECT_EQ(check_message(m), "start barrier bitset too long");
  m.barrier_ready.pop_back();
  for (const double bad : {std::nan(""), 1e300}) {
    m.barrier_ready_at_s = bad;
    EXPECT_EQ(check_message(m), "start barrier instant not finite or absurd");
  }
}

TEST(WireBound, OneMoreThanTheWireCarriesIsRefusedNotCut) {
  qswarm_msgs::AgentState s;
  EXPECT_THROW(to_idl(with_entries(kMaxSwarmAgents), s), std::length_error);
}

}  // namespace
}  // namespace qswarm
