// The fault model: seeded per-link streams (a run replays), Gilbert-Elliott bursts, windows.
#include <gtest/gtest.h>

#include <algorithm>

#include "common/runtime/faulty_bus.hpp"
#include "common/scenario/fault_plan.hpp"
#include "common/transport/in_memory_bus.hpp"

namespace qswarm {
namespace {

std::vector<bool> drops(LinkFaults& f, AgentId from, int n, double t = 1.0) {
  std::vector<bool> out;
  out.reserve(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) out.push_back(f.on_receive(from, t).drop);
  return out;
}

TEST(LinkFaults, SameSeedReplaysAndLinksHaveIndependentStreams) {
  FaultPlan plan;
  plan.loss.push_back({0.3, 0, 0, 0.0, 0.0});
  LinkFaults a(plan, 2, 42), b(plan, 2, 42), c(plan, 2, 43);
  const auto da = drops(a, 1, 2000), db = drops(b, 1, 2000), dc = drops(c, 1, 2000);
  EXPECT_EQ(da, db);  // same seed, same link: identical decisions
  EXPECT_NE(da, dc);  // another seed: another stream
  LinkFaults d(plan, 2, 42);
  EXPECT_NE(drops(d, 3, 2000), da);  // another link: another stream
  const double rate = static_cast<double>(std::count(da.begin(), da.end(), true)) / 2000.0;
  EXPECT_NEAR(rate, 0.3, 0.03);
  EXPECT_EQ(a.counters().loss, static_cast<std::uint64_t>(std::count(da.begin(), da.end(), true)));
}

TEST(LinkFaults, GilbertElliottLosesInBursts) {
  // Good->bad 5%, bad->good 25%: stationary loss 0.05/(0.05+0.25) = 1/6, mean burst 1/0.25 = 4.
  FaultPlan plan;
  plan.burst.push_back({0.05, 0.25, 0.0, 1.0, 0, 0});
  LinkFaults f(plan, 1, 9);
  const auto d = drops(f, 2, 200000);
  const double rate =
      static_cast<double>(std::count(d.begin(), d.end(), true)) / static_cast<double>(d.size());
  int bursts = 0, lost = 0;
  for (size_t i = 0; i < d.size(); ++i) {
    lost += d[i];
    if (d[i] && (i == 0 || !d[i - 1])) ++bursts;
  }
  EXPECT_NEAR(rate, 1.0 / 6.0, 0.01);
  EXPECT_NEAR(static_cast<double>(lost) / bursts, 4.0, 0.2);
}

TEST(LinkFaults, CutsAndPartitionsHoldOnlyInsideTheirWindows) {
  FaultPlan plan;
  plan.cut.push_back({1, 2, 5.0, 15.0, false});
  plan.partition.push_back({{1, 3}, 20.0, 30.0});
  LinkFaults at2(plan, 2, 1), at4(plan, 4, 1);
  EXPECT_FALSE(at2.on_receive(1, 4.9).drop);
  EXPECT_TRUE(at2.on_receive(1, 5.0).drop);
  EXPECT_TRUE(at2.on_receive(1, 14.9).drop);
  EXPECT_FALSE(at2.on_receive(1, 15.0).drop);
  EXPECT_FALSE(at2.on_receive(3, 10.0).drop);  // other links untouched
  EXPECT_TRUE(at4.on_receive(1, 25.0).drop);   // 1 is in the group, 4 is not
  EXPECT_TRUE(at4.on_receive(3, 25.0).drop);
  EXPECT_FALSE(at2.on_receive(5, 25.0).drop);  // both outside the group
  EXPECT_FALSE(at4.on_receive(1, 30.0).drop);  // healed
  EXPECT_EQ(at2.counters().cut, 2u);
  EXPECT_EQ(at4.counters().partition, 2u);
}

TEST(FaultyBus, DelayHoldsMessagesAndKeepsTheNewest) {
  // Given agent 1's endpoint decorated with a 0.1 +- 0.05 s delay, and agent 2 sending to it
  InMemoryNetwork net;
  InMemoryBus inner(net), sender(net);
  FaultPlan plan;
  plan.delay.push_back({0.1, 0.05, 0, 0});
  FaultyBus bus(inner, LinkFaults(plan, 1, 5), 1);
  StateMessage m;
  m.view.id = 2;
  m.seq = 1;
  bus.set_time(0.0);
  sender.publish(m);
  net.deliver();
  EXPECT_TRUE(bus.latest(1).empty());  // still held
  m.seq = 2;
  bus.set_time(0.01);
  sender.publish(m);
  net.deliver();
  bus.set_time(0.5);
  const auto got = bus.latest(1);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].seq, 2u);  // a reordered older one never replaces the newest
  EXPECT_EQ(bus.fault_counters().delayed, 2u);
}

TEST(FaultyBus, ItsListenerHearsWhatSurvivesAndNothingOnceUnregistered) {
  InMemoryNetwork net;
  InMemoryBus inner(net), sender(net);
  FaultPlan plan;
  plan.cut.push_back({1, 2, 1.0, 2.0, false});
  FaultyBus bus(inner, LinkFaults(plan, 1, 5), 1);
  int heard = 0;
  bus.set_listener([&](const StateMessage&) { ++heard; });
  StateMessage m;
  m.view.id = 2;
  for (std::uint64_t k = 1; k <= 4; ++k) {
    bus.set_time(0.5 * static_cast<double>(k));  // 0.5, 1.0, 1.5, 2.0: the cut drops 1.0 and 1.5
    m.seq = k;
    sender.publish(m);
    net.deliver();
  }
  EXPECT_EQ(heard, 2);
  bus.set_listener(nullptr);
  m.seq = 9;
  sender.publish(m);
  net.deliver();
  EXPECT_EQ(heard, 2);
}

TEST(FaultyBus, WithNoLinkFaultsPlannedItPassesEverySampleThroughUnchanged) {
  // Given a plan with only a kill (no link fault): the decorator stands aside
  InMemoryNetwork net;
  InMemoryBus inner(net), sender(net), other(net);
  FaultPlan plan;
  plan.kill.push_back({3, 10.0, 20.0});
  ASSERT_TRUE(LinkFaults(plan, 1, 5).none());
  FaultyBus bus(inner, LinkFaults(plan, 1, 5), 1);
  std::vector<std::uint64_t> heard;
  bus.set_listener([&](const StateMessage& m) { heard.push_back(m.seq); });
  StateMessage m;
  m.view.id = 2;
  for (std::uint64_t k = 1; k <= 3; ++k) {
    bus.set_time(0.5 * static_cast<double>(k));
    m.seq = k;
    sender.publish(m);
    net.deliver();
  }
  StateMessage mine;  // a sample keyed as the decorated agent itself is never its neighbour
  mine.view.id = 1;
  mine.seq = 1;
  other.publish(mine);
  net.deliver();
  // Then its listener heard every sample at once, and latest() is the transport's newest
  EXPECT_EQ(heard, (std::vector<std::uint64_t>{1, 2, 3}));
  const auto got = bus.latest(1);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].seq, 3u);
  EXPECT_EQ(bus.fault_counters(), FaultCounters{});
  // And any link fault, even one that starts later, puts it back in the path
  plan.loss.push_back({0.5, 0, 0, 100.0, 0.0});
  EXPECT_FALSE(LinkFaults(plan, 1, 5).none());
}

TEST(FaultPlan, TimelineAndLastFaultEnd) {
  FaultPlan plan;
  plan.cut.push_back({1, 2, 5.0, 15.0, false});
  plan.kill.push_back({3, 10.0, 20.0});
  EXPECT_DOUBLE_EQ(plan.last_fault_end_s(), 20.0);
  const auto tl = plan.timeline();
  ASSERT_EQ(tl.size(), 4u);
  EXPECT_EQ(tl[0].kind, "cut");
  EXPECT_EQ(tl[1].kind, "kill");
  EXPECT_EQ(tl[2].kind, "cut_end");
  EXPECT_EQ(tl[3].kind, "restart");
}

}  // namespace
}  // namespace qswarm
