// No silent bounds on the wire: a state message carries every link, flow and copy of the largest
// swarm a scenario allows, and refuses (never cuts) more.
#include <gtest/gtest.h>

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

TEST(WireBound, OneMoreThanTheWireCarriesIsRefusedNotCut) {
  qswarm_msgs::AgentState s;
  EXPECT_THROW(to_idl(with_entries(kMaxSwarmAgents), s), std::length_error);
}

}  // namespace
}  // namespace qswarm
