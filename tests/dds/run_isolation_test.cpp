// Two runs on one DDS domain never hear each other; a supervisor that listens to every run's
// partition hears the other run and says so.
#include <gtest/gtest.h>

#include "common/dds/dds_bus.hpp"
#include "common/transport/sample_gate.hpp"
#include "tests/swarm/domain_lease.hpp"
#include "tests/swarm/harness.hpp"

namespace qswarm {
namespace {

DdsOptions options(std::uint64_t run, const char* name, bool all = false) {
  DdsOptions o;
  o.domain_id = static_cast<std::uint32_t>(test::test_domain().domain());
  o.participant_name = name;
  o.max_agents = 16;
  o.run_id = run;
  o.hear_all_runs = all;
  return o;
}

StateMessage sample(AgentId id, std::uint64_t run, std::uint64_t seq) {
  StateMessage m;
  m.view.id = id;
  m.seq = seq;
  m.run_id = run;
  m.phase = kRunning;
  return m;
}

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
        run_a.publish(sample(1, 0xA, seq));
        run_b_peer.publish(sample(2, 0xB, seq));
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
        impostor.publish(sample(3, 0xD, ++seq));  // in run C's partition, claiming run D
        return receiver.counters().foreign > 3;
      },
      30.0));
  EXPECT_TRUE(receiver.latest(0).empty());
}

TEST(SampleGate, AnIncarnationFromTheFutureCannotLockTheRealAgentOut) {
  SampleGate gate;
  const std::int64_t now = wall_now_ns();
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
