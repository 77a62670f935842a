// Two runs on one DDS domain never hear each other; a supervisor that listens to every run's
// partition hears the other run and says so.
#include <gtest/gtest.h>

#include <cstring>

#include <memory>
#include <vector>

#include "common/dds/dds_bus.hpp"
#include "common/dds/idl_convert.hpp"
#include "common/dds/roster_filter.hpp"
#include "common/transport/sample_gate.hpp"
#include "swarm_statePubSubTypes.h"
#include "tests/dds/test_bus.hpp"
#include "tests/swarm/domain_lease.hpp"
#include "tests/swarm/harness.hpp"

namespace qswarm {
namespace {

DdsOptions options(std::uint64_t run, const char* name, bool all = false) {
  DdsOptions o = test::dds_options(name, run);
  o.state.hear_all_runs = all;
  return o;
}

using test::state_sample;

TEST(RunIsolation, ARunOnTheSameDomainIsNeverHeardAndASupervisorSaysItIsThere) {
  DdsBus run_a(options(0xA, "run-a-agent"));
  DdsBus run_b(options(0xB, "run-b-agent"));
  DdsBus run_b_supervisor(options(0xB, "run-b-supervisor", /*all=*/true));
  DdsBus run_b_peer(options(0xB, "run-b-peer"));
  std::uint64_t seq = 0;
  // Until run B's own peer and the supervisor have heard run B, and the supervisor run A too
  ASSERT_TRUE(test::wait_for(
      [&] {
        ++seq;
        run_a.publish(state_sample(1, 0xA, seq));
        run_b_peer.publish(state_sample(2, 0xB, seq));
        return run_b.counters().received > 5 && run_b_supervisor.counters().foreign > 5 &&
               run_b_supervisor.counters().received > 5;
      },
      30.0));
  // run B's agent never received a sample of run A (the partitions never matched)
  for (const StateMessage& m : run_b.latest(0)) EXPECT_EQ(m.run_id, 0xBu);
  EXPECT_EQ(run_b.counters().foreign, 0u);
  EXPECT_EQ(run_b.latest(0).size(), 1u);
  // and the supervisor refused run A's samples, naming the run
  EXPECT_EQ(run_b_supervisor.foreign_runs(), std::set<std::uint64_t>{0xA});
  EXPECT_EQ(run_b_supervisor.latest(0).size(), 1u);  // only agent 2 of run B
}

TEST(RunIsolation, ASampleCarryingAnotherRunsIdInsideThePartitionIsRefused) {
  DdsBus receiver(options(0xC, "receiver"));
  DdsBus impostor(options(0xC, "impostor"));
  std::uint64_t seq = 0;
  ASSERT_TRUE(test::wait_for(
      [&] {
        impostor.publish(state_sample(3, 0xD, ++seq));  // in run C's partition, claiming run D
        return receiver.counters().foreign > 3;
      },
      30.0));
  EXPECT_TRUE(receiver.latest(0).empty());
}

TEST(RosterFilter, RangesOfConsecutiveIdsBothWays) {
  EXPECT_EQ(roster_filter({}), "");
  EXPECT_EQ(roster_filter({3, 1, 2, 2}), "1-3");
  EXPECT_EQ(roster_filter({7, 1, 2, 9, 10}), "1-2,7,9-10");
  EXPECT_EQ(roster_filter({4294967295u}), "4294967295");
  EXPECT_EQ(roster_filter({1, 2, 3}, 2), "1-3;self=2");
  using Ranges = std::vector<std::pair<AgentId, AgentId>>;
  EXPECT_EQ(parse_roster_filter("1-2,7,9-10"), (RosterExpression{Ranges{{1, 2}, {7, 7}, {9, 10}}}));
  EXPECT_EQ(parse_roster_filter("4294967295"),
            (RosterExpression{Ranges{{4294967295u, 4294967295u}}}));
  EXPECT_EQ(parse_roster_filter("1-3;self=2"), (RosterExpression{Ranges{{1, 3}}, 2}));
  for (const char* bad : {"",
                          ",",
                          "1,",
                          ",1",
                          "1-",
                          "-1",
                          "3-1",
                          "1;2",
                          "4294967296",
                          "1--2",
                          "12345678901",
                          "a",
                          "1-2-3",
                          "1;self=",
                          "1;self=0",
                          "1;every=0",
                          "1;self=2;self=3",
                          "1;every=2;every=2",
                          "1;speed=2",
                          ";self=1",
                          "1;self=2x",
                          "1;every=1000001"})
    EXPECT_FALSE(parse_roster_filter(bad).has_value()) << bad;
}

// The filter reads the id at a fixed place of a serialized sample: it must be where the generated
// type puts it.
TEST(RosterFilter, ReadsItsFieldsWhereTheSerializedSampleHasThem) {
  StateMessage m;
  m.view.id = 0x01020304u;
  m.seq = 0x1122334455667788ull;
  m.phase = Phase::kReady;
  m.links = {{2, 1.0}};
  qswarm_msgs::AgentState s;
  to_idl(m, s);
  qswarm_msgs::AgentStatePubSubType type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(type.m_typeSize);
  ASSERT_TRUE(type.serialize(&s, &payload));
  ASSERT_GE(payload.length, kRosterIdOffset + 4);
  const unsigned char* d = payload.data;
  ASSERT_EQ(d[1] & 1, 1) << "little-endian CDR expected on this host";
  std::uint32_t id = 0;
  std::memcpy(&id, d + kRosterIdOffset, 4);
  EXPECT_EQ(id, m.view.id);
}

// The place filter reads the consensus state and the physical position the same way.
TEST(RosterFilter, ReadsThePlacesWhereTheSerializedSampleHasThem) {
  StateMessage m;
  m.view.id = 7;
  m.view.q = Vec3(1.5, -2.25, 3.125);
  m.p_W = Vec3(-7.5, 8.25, 9.0625);
  m.links = {{2, 1.0}};
  qswarm_msgs::AgentState s;
  to_idl(m, s);
  qswarm_msgs::AgentStatePubSubType type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(type.m_typeSize);
  ASSERT_TRUE(type.serialize(&s, &payload));
  ASSERT_GE(payload.length, kPositionOffset + 24);
  double q[3], p[3];
  std::memcpy(q, payload.data + kConsensusOffset, sizeof q);
  std::memcpy(p, payload.data + kPositionOffset, sizeof p);
  EXPECT_EQ(Vec3(q[0], q[1], q[2]), m.view.q);
  EXPECT_EQ(Vec3(p[0], p[1], p[2]), m.p_W);
}

TEST(RunIsolation, AStrangerFloodingKeysOnTheRunsPartitionCannotBlindAReader) {
  // 60 keys outside the run's roster (six participants of 10 keys each: a writer keeps 10
  // instances) would fill a reader sized for 16 agents + 16; with the roster filter they never
  // take a slot, and the run's own agents are still heard.
  DdsOptions o = options(0xE, "receiver");
  o.state.roster = {1, 2, 3, 4};
  DdsBus receiver(o);
  std::vector<std::unique_ptr<DdsBus>> strangers;
  strangers.reserve(6);
  for (int k = 0; k < 6; ++k)
    strangers.push_back(std::make_unique<DdsBus>(options(0xE, "stranger")));
  std::uint64_t seq = 0;
  ASSERT_TRUE(test::wait_for(  // the strangers come first
      [&] {
        ++seq;
        for (std::size_t k = 0; k < strangers.size(); ++k)
          for (AgentId id = 0; id < 10; ++id)
            strangers[k]->publish(state_sample(100 + 10 * static_cast<AgentId>(k) + id, 0xE, seq));
        return receiver.strangers().size() + receiver.latest(0).size() >= 60;
      },
      30.0));
  DdsBus agents(options(0xE, "agents"));
  ASSERT_TRUE(test::wait_for(
      [&] {
        ++seq;
        for (AgentId id = 1; id <= 4; ++id) agents.publish(state_sample(id, 0xE, seq));
        return receiver.latest(0).size() == 4;
      },
      30.0));
  for (const StateMessage& m : receiver.latest(0)) EXPECT_LE(m.view.id, 4u);
  // The strangers are told apart and counted, not silently lost.
  for (const AgentId id : receiver.strangers()) EXPECT_TRUE(id >= 100 && id < 160) << id;
  EXPECT_GE(receiver.counters().dropped, 60u);
}

TEST(SampleGate, AnIncarnationFromTheFutureCannotLockTheRealAgentOut) {
  SampleGate gate;
  const std::int64_t now = system_clock().wall_ns();
  StateMessage forged;
  forged.view.id = 2;
  forged.seq = 1u << 30;
  forged.incarnation = now + 1'000'000'000'000LL;  // 1000 s ahead
  const SampleGate::Result r = gate.admit(forged, check_message(forged), now);
  EXPECT_EQ(r.verdict, SampleGate::Verdict::kInvalid);
  EXPECT_NE(r.why.find("future"), std::string::npos);
  StateMessage real;
  real.view.id = 2;
  real.seq = 5;
  real.incarnation = now - 1'000'000'000;  // started a second ago
  EXPECT_EQ(gate.admit(real, check_message(real), now).verdict, SampleGate::Verdict::kAccepted);
}

}  // namespace
}  // namespace qswarm
