// What runs beside a transport's threads, with real threads: samples arrive on a feeder thread (as
// DDS delivers them) while the owner polls, reads and tears down. These tests are CI's
// ThreadSanitizer stage (tools/test.sh): they pass as plain tests, and TSan reports any data race.
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <thread>

#include <unistd.h>

#include "common/claim/claim_bus.hpp"
#include "common/record/run_observer.hpp"
#include "common/record/supervisor_loop.hpp"
#include "common/runtime/agent_loop.hpp"
#include "common/runtime/faulty_bus.hpp"
#include "common/scenario/scenario.hpp"
#include "tests/runtime/threaded_bus.hpp"
#include "tests/support/plan_for.hpp"

namespace qswarm {
namespace {

using test::ThreadFedBus;

StateMessage running_sample(AgentId id, std::uint64_t seq, double t_s) {
  StateMessage m;
  m.view.id = id;
  m.view.seq = seq;
  m.view.q = Vec3(static_cast<double>(id), 0.0, 10.0);
  m.view.q0 = m.view.q;
  m.p_W = m.view.q;
  m.seq = seq;
  m.stamp_s = t_s;
  m.phase = Phase::kRunning;
  m.incarnation = 1;
  return m;
}

// Two agents 2 m apart, for the supervisor's loop.
RunConfig two_agents() {
  return resolve_scenario(
      parse_scenario_text("agents { id: 1 position { x: 0 y: 0 z: 10 } }\n"
                          "agents { id: 2 position { x: 2 y: 0 z: 10 } }\n"
                          "duration_s: 1000\n",
                          "two"));
}

// An empty directory of this test process's own under the temporary directory.
std::filesystem::path fresh_dir(const std::string& tag) {
  std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("qswarm-" + tag + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  return dir;
}

// Feeds running samples of `ids` into `bus` from its own thread until stopped.
class Feeder {
 public:
  Feeder(ThreadFedBus& bus, std::vector<AgentId> ids)
      : thread_([this, &bus, ids = std::move(ids)] {
          std::uint64_t seq = 0;
          while (!stop_) {
            ++seq;
            for (const AgentId id : ids)
              bus.feed(running_sample(id, seq, 0.01 * static_cast<double>(seq)));
            fed_ = seq;
          }
          samples_ = seq * ids.size();
        }) {}
  ~Feeder() { stop(); }
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  // Waits (yielding) until at least n rounds were fed: a condition, not a sleep.
  void wait_for_rounds(std::uint64_t n) const {
    while (fed_ < n) std::this_thread::yield();
  }
  // Samples fed, once stopped.
  std::uint64_t samples() const { return samples_; }

 private:
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> samples_{0};
  std::atomic<std::uint64_t> fed_{0};
  std::thread thread_;
};

TEST(Concurrency, AFaultyBusFedFromAnotherThreadServesItsOwnerAndUnregistersSafely) {
  // Given the fault decorator (loss and jitter) on a transport fed from another thread
  ThreadFedBus inner;
  FaultPlan plan;
  plan.loss.push_back({0.3, 0, 0, 0.0, 0.0});
  plan.delay.push_back({0.01, 0.005, 0, 0});
  std::atomic<int> heard{0};
  {
    FaultyBus bus(inner, LinkFaults(plan, 1, 7), 1);
    bus.set_listener([&](const StateMessage&) { ++heard; });
    Feeder feeder(inner, {2, 3, 4});
    feeder.wait_for_rounds(50);
    // When its owner moves time on, reads and counts while samples arrive
    for (int k = 0; k < 2000; ++k) {
      bus.set_time(0.001 * k);
      const std::vector<StateMessage> got = bus.latest(1);
      for (const StateMessage& m : got) EXPECT_NE(m.view.id, 1u);
      (void)bus.fault_counters();
      (void)bus.counters();
    }
    // Then it is destroyed while the feeder still delivers (it unregisters first)
  }
  EXPECT_GT(heard.load(), 0);
}

TEST(Concurrency, AFaultyBusWithNoFaultsPlannedPassesSamplesThroughFromAnotherThread) {
  ThreadFedBus inner;
  std::atomic<int> heard{0}, heard_self{0};
  {
    FaultyBus bus(inner, LinkFaults(FaultPlan{}, 1, 7), 1);
    bus.set_listener([&](const StateMessage& m) { ++(m.view.id == 1 ? heard_self : heard); });
    Feeder feeder(inner, {1, 2, 3});
    feeder.wait_for_rounds(50);
    for (int k = 0; k < 2000; ++k) {
      bus.set_time(0.001 * k);
      for (const StateMessage& m : bus.latest(1)) EXPECT_NE(m.view.id, 1u);
    }
    bus.set_listener(nullptr);
  }
  EXPECT_GT(heard.load(), 0);
  EXPECT_EQ(heard_self.load(), 0);
}

TEST(Concurrency, AnAgentLoopFliesWhileItsTransportDeliversFromAnotherThread) {
  // Given agent 1 of a two-agent run, and agent 2's samples arriving on a transport thread
  const RunConfig rc = resolve_scenario(parse_scenario_text(
      "agents { id: 1 position { x: 0 y: 0 z: 10 } }\n"
      "agents { id: 2 position { x: 2 y: 0 z: 10 } }\n"
      "weight { policy: UNWEIGHTED } topology { policy: PROXIMITY threshold_m: 100 }\n",
      "two"));
  ThreadFedBus bus;
  ManualClock clock;  // the loop's own thread is the only one that reads it
  AgentLoopOptions o;
  AgentLoop loop(rc, 1, o, bus, clock);
  Feeder feeder(bus, {2});
  feeder.wait_for_rounds(10);  // agent 2 is heard running before agent 1's first poll
  // When it polls through the barrier and a few hundred ticks
  for (int k = 0; k < 100000 && loop.ticks() < 300; ++k) {
    const AgentLoop::Poll p = loop.poll();
    clock.sleep_until(p.wake_at_s);
  }
  loop.stop();
  feeder.stop();
  // Then it ran, hearing its neighbour all along
  EXPECT_EQ(loop.phase(), LifePhase::kStopping);
  EXPECT_GE(loop.ticks(), 300u);
  EXPECT_GT(loop.transport_counters().received, 0u);
}

TEST(Concurrency, TheSupervisorRecordsSamplesArrivingWhileItPolls) {
  // Given the supervisor's loop on a transport fed from another thread
  const RunConfig rc = two_agents();
  const std::filesystem::path dir = fresh_dir("concurrency");
  const RunDir run = RunDir::claim(dir.string(), "two", "t");
  ThreadFedBus bus;
  SteadyClock clock;  // read on the feeder's thread too, as DDS threads do
  SupervisorOptions so;
  so.progress = true;
  SupervisorLoop sup(rc, run, so, bus, clock);
  {
    Feeder feeder(bus, {1, 2, 9});  // 9 is a stranger
    feeder.wait_for_rounds(20);
    // When it polls while samples keep arriving, then finishes while they still do
    for (int k = 0; k < 500; ++k) (void)sup.poll(false);
    sup.finish("interrupted");
  }
  // Then the record is complete and says what it heard
  EXPECT_TRUE(sup.complete());
  EXPECT_EQ(sup.exit_code(), 1);
  EXPECT_GT(std::filesystem::file_size(run.telemetry()), 100u);
  std::filesystem::remove_all(dir);
}

TEST(Concurrency, ASupervisorThatFallsBehindHoldsAtMostItsInboxAndSaysWhatItDidNotRecord) {
  // Given the supervisor's loop with an inbox of 40 samples, on a transport fed from another thread
  const RunConfig rc = two_agents();
  const std::filesystem::path dir = fresh_dir("behind");
  const RunDir run = RunDir::claim(dir.string(), "two", "t");
  ThreadFedBus bus;
  SteadyClock clock;
  SupervisorOptions so;
  so.inbox_max = 40;
  SupervisorLoop sup(rc, run, so, bus, clock);
  // When 200 samples or more arrive before it polls
  std::uint64_t fed = 0;
  {
    Feeder feeder(bus, {1, 2});
    feeder.wait_for_rounds(100);
    feeder.stop();
    fed = feeder.samples();
  }
  ASSERT_GE(fed, 200u);
  EXPECT_EQ(sup.inbox_overflow(), fed - 40);
  const SupervisorLoop::Poll p = sup.poll(false);
  // Then it recorded the 40 its inbox held, in order, and says once that it fell behind
  ASSERT_EQ(p.warnings.size(), 1u);
  EXPECT_NE(p.warnings[0].find("faster than the supervisor records them"), std::string::npos);
  EXPECT_TRUE(sup.poll(false).warnings.empty());
  const std::string text = sup.finish("interrupted");
  EXPECT_NE(text.find("received 40,"), std::string::npos) << text;
  EXPECT_NE(text.find("BEHIND: " + std::to_string(fed - 40) + " samples"), std::string::npos)
      << text;
  std::ifstream summary(run.summary());
  const std::string json((std::istreambuf_iterator<char>(summary)), {});
  EXPECT_NE(json.find("\"unrecorded\": " + std::to_string(fed - 40)), std::string::npos);
  std::ifstream events(run.events());
  const std::string csv((std::istreambuf_iterator<char>(events)), {});
  EXPECT_NE(csv.find("supervisor_behind"), std::string::npos);
  EXPECT_EQ(sup.exit_code(), 1);
  std::filesystem::remove_all(dir);
}

// A watcher of the record that makes recording slow: each sample it is shown moves the clock on.
class SlowRecording final : public RunObserver {
 public:
  SlowRecording(ManualClock& clock, double per_record_s) : clock_(clock), dt_(per_record_s) {}
  void on_record(const records::Record& r, std::int64_t) noexcept override {
    if (r.has_sample()) clock_.advance(dt_);
  }
  void on_summary(const records::Summary&) noexcept override {}

 private:
  ManualClock& clock_;
  double dt_;
};

TEST(Concurrency, ASupervisorThatRecordsSlowlyJudgesSilenceWhenTheSamplesArrivedNotWhenItCaughtUp) {
  // Given the supervisor on a manual clock, its agents heard every 0.1 s for 2 s
  const RunConfig rc = two_agents();
  const std::filesystem::path dir = fresh_dir("slow");
  const RunDir run = RunDir::claim(dir.string(), "two", "t");
  ThreadFedBus bus;
  ManualClock clock;
  SupervisorOptions so;
  so.inbox_max = 1000;
  SupervisorLoop sup(rc, run, so, bus, clock);
  std::uint64_t seq = 0;
  for (; seq < 20; ++seq) {
    for (const AgentId id : {1u, 2u})
      bus.feed(running_sample(id, seq + 1, 0.1 * static_cast<double>(seq)));
    clock.advance(0.1);
  }
  // When recording them takes 0.2 s a sample (8 s in all, eight neighbour timeouts)
  SlowRecording slow(clock, 0.2);
  sup.set_observer(&slow);
  (void)sup.poll(false);
  sup.set_observer(nullptr);
  EXPECT_GT(clock.now_s(), 9.0);
  // Then nobody departed: both were heard until the instant the samples were taken
  EXPECT_EQ(sup.recorder().departures(), 0u);
  // And silence is still silence: two seconds on with nothing heard, both have departed
  clock.advance(0.1);
  (void)sup.poll(false);
  EXPECT_EQ(sup.recorder().departures(), 2u);
  sup.finish("interrupted");
  std::filesystem::remove_all(dir);
}

TEST(Concurrency, AClaimInboxHeardOnOneThreadIsReadOnAnother) {
  const std::size_t kept = test::plan_for(8).claim_capacity;
  ClaimInbox inbox(5, kept);
  std::atomic<bool> stop{false};
  std::atomic<std::uint64_t> heard{0};
  std::thread hearer([&] {
    for (std::uint64_t n = 1; !stop; n = n % 100 + 1) {
      inbox.hear(IdClaim{n, n, 5, 8, 0, 0, 0.0});
      ++heard;
    }
  });
  std::size_t most = 0;
  while (heard < 5000) most = std::max(most, inbox.claims().size());
  stop = true;
  hearer.join();
  EXPECT_LE(most, kept);
  EXPECT_GT(inbox.evicted(), 0u);
}

}  // namespace
}  // namespace qswarm
