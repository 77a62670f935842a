// A participant that reads its sockets at its tick (TickReceive): it starts no receive thread,
// hears nothing until its owner drains, and then hears and is heard like a threaded one.
#include <dirent.h>
#include <gtest/gtest.h>

#include <memory>

#include "common/dds/dds_bus.hpp"
#include "common/dds/participant.hpp"
#include "common/dds/tick_transport.hpp"
#include "tests/dds/test_bus.hpp"
#include "tests/swarm/harness.hpp"

namespace qswarm {
namespace {

constexpr std::uint64_t kRun = 0x71c;

int threads_of_this_process() {
  int n = 0;
  if (DIR* d = ::opendir("/proc/self/task")) {
    while (const dirent* e = ::readdir(d)) n += e->d_name[0] != '.';
    ::closedir(d);
  }
  return n;
}

DdsOptions at_the_tick(const char* name) {
  DdsOptions o = test::dds_options(name, kRun);
  o.participant.tick_receive = true;
  return o;
}

TEST(TickReceive, StartsNoReceiveThreadAndHearsOnlyWhenItsOwnerDrains) {
  DdsBus first(test::dds_options("first", kRun));  // the process's own Fast DDS threads start
  int before = threads_of_this_process();
  DdsBus threaded(test::dds_options("threaded", kRun));
  const int threaded_threads = threads_of_this_process() - before;
  before = threads_of_this_process();
  DdsBus tick(at_the_tick("tick"));
  const int tick_threads = threads_of_this_process() - before;
  ASSERT_NE(tick.participant().tick_receive(), nullptr);
  EXPECT_EQ(threaded.participant().tick_receive(), nullptr);
  // Fast DDS's UDPv4 reads each of a participant's three sockets (discovery multicast and
  // unicast, user unicast) with a thread of its own; the tick's participant reads them itself.
  EXPECT_LE(tick_threads + 3, threaded_threads)
      << "threads: " << tick_threads << " at the tick, " << threaded_threads << " threaded";
  TickReceive& rx = *tick.participant().tick_receive();
  EXPECT_GE(rx.fds().size(), 3u);

  // A sample on the wire (a threaded peer hears it) is not heard by the tick's participant, which
  // has not even discovered anyone: nothing read its sockets.
  std::uint64_t seq = 0;
  ASSERT_TRUE(test::wait_for(
      [&] {
        first.publish(test::state_sample(1, kRun, ++seq));
        return !threaded.latest(0).empty();
      },
      30.0));
  EXPECT_TRUE(tick.latest(0).empty());
  EXPECT_EQ(rx.counters().datagrams, 0u);

  // Drained as a loop would, it discovers, hears agent 1, and is heard.
  ASSERT_TRUE(test::wait_for(
      [&] {
        rx.drain();
        first.publish(test::state_sample(1, kRun, ++seq));
        tick.publish(test::state_sample(2, kRun, seq));
        bool heard_by_first = false;
        for (const StateMessage& m : first.latest(0)) heard_by_first |= m.view.id == 2;
        return !tick.latest(0).empty() && heard_by_first;
      },
      30.0));
  const TickReceive::Counters c = rx.counters();
  EXPECT_GT(c.datagrams, 0u);
  EXPECT_GT(c.drains, 0u);
  EXPECT_EQ(c.truncated, 0u);
  EXPECT_EQ(c.errors, 0u);
}

TEST(TickReceive, ADrainingClockReadsWhatArrivedAfterEachWait) {
  DdsBus peer(test::dds_options("peer", kRun));
  DdsBus tick(at_the_tick("tick"));
  DrainingClock clock;
  clock.drain(tick.participant().tick_receive());
  std::uint64_t seq = 0;
  // Only the clock's waits read the sockets here.
  bool heard = false;
  for (int i = 0; i < 1500 && !heard; ++i) {
    peer.publish(test::state_sample(1, kRun, ++seq));
    clock.sleep_until(clock.now_s() + 0.02);
    heard = !tick.latest(0).empty();
  }
  EXPECT_TRUE(heard);
  EXPECT_GT(tick.participant().tick_receive()->counters().drains, 0u);
}

}  // namespace
}  // namespace qswarm
