// The record stream (agent to supervisor): an agent is told the supervisor hears it only once the
// supervisor has what it sent. The start barrier waits on this, so a writer-side match that the
// supervisor has not yet made (a lost discovery message, repaired a second later) cannot start a
// run whose record misses an agent's first seconds.
#include <gtest/gtest.h>

#include <thread>

#include "common/dds/dds_bus.hpp"
#include "tests/dds/test_bus.hpp"
#include "tests/swarm/domain_lease.hpp"
#include "tests/swarm/harness.hpp"

namespace qswarm {
namespace {

constexpr std::uint64_t kRun = 0x5EC0;

DdsOptions options(const char* name, bool recorder) {
  DdsOptions o = test::dds_options(name, kRun, recorder);
  o.state.hear_all_runs = false;  // this run's record stream only
  return o;
}

StateMessage sample(AgentId id, std::uint64_t seq) {
  return test::state_sample(id, kRun, seq, Phase::kWaiting);  // an agent at its start barrier
}

TEST(RecordStream, AnAgentIsConfirmedOnlyWhenTheRecorderAlreadyHoldsItsSample) {
  DdsBus agent(options("record-agent", false));
  std::uint64_t seq = 0;
  for (int i = 0; i < 20; ++i) agent.record(sample(4, ++seq));
  EXPECT_FALSE(agent.recorder_confirmed());  // nobody records this run

  DdsBus recorder(options("record-supervisor", true));
  bool held_when_confirmed = false;
  ASSERT_TRUE(test::wait_for(
      [&] {
        if (agent.recorder_confirmed()) {
          // Acknowledged means received: the recorder already took a sample of agent 4.
          held_when_confirmed = recorder.latest(0).size() == 1 && recorder.counters().received > 0;
          return true;
        }
        agent.record(sample(4, ++seq));
        return false;
      },
      30.0));
  EXPECT_TRUE(held_when_confirmed);
  // The agent's state stream is not the record: the recorder heard nothing else.
  EXPECT_EQ(recorder.latest(0).front().view.id, 4u);
}

TEST(RecordStream, AMatchOnlyTheAgentSawIsNotConfirmation) {
  // The agent's writer announcements are lost: it matches the recorder's reader, the recorder
  // never learns its writer and drops what it sends. The agent must not take that match for
  // being heard (the start barrier would start a run whose record misses it).
  DdsOptions o = options("record-agent-unannounced", false);
  o.participant.test_drop_writer_announcements = true;
  DdsBus agent(o);
  DdsBus recorder(options("record-supervisor-3", true));
  std::uint64_t seq = 0;
  ASSERT_TRUE(test::wait_for(
      [&] {
        agent.record(sample(6, ++seq));
        return agent.record_readers_matched() == 1;
      },
      30.0));
  for (int i = 0; i < 200; ++i) {
    agent.record(sample(6, ++seq));
    ASSERT_FALSE(agent.recorder_confirmed()) << "after " << i << " samples";
    std::this_thread::yield();
  }
  EXPECT_EQ(recorder.counters().received, 0u);
}

TEST(RecordStream, ARecorderThatLeftConfirmsNothingMore) {
  DdsBus agent(options("record-agent-2", false));
  std::uint64_t seq = 0;
  {
    DdsBus recorder(options("record-supervisor-2", true));
    ASSERT_TRUE(test::wait_for(
        [&] {
          if (agent.recorder_confirmed()) return true;
          agent.record(sample(5, ++seq));
          return false;
        },
        30.0));
  }
  // Once the recorder left, nothing the agent records is confirmed again.
  ASSERT_TRUE(test::wait_for(
      [&] {
        agent.record(sample(5, ++seq));
        return !agent.recorder_confirmed();
      },
      30.0));
}

}  // namespace
}  // namespace qswarm
