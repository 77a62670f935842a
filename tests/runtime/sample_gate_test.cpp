// The sample gate against forgers it cannot keep out (a plain run: anyone on the network can
// publish an agent's key). It names two writers at once, sequence jumps and incarnations from the
// future, and never locks the real agent out for good: once a forger stops, the real agent is
// heard again, whatever numbers the forger used.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "common/core/law_registry.hpp"
#include "common/transport/sample_gate.hpp"

namespace qswarm {
namespace {

constexpr std::int64_t kNow = 1'700'000'000'000'000'000;  // the receiver's wall clock [ns]
constexpr std::int64_t kMs = 1'000'000;

WriterId writer(std::uint8_t n) {
  WriterId w;
  w.bytes[0] = n;
  w.bytes[15] = 3;
  return w;
}

StateMessage sample(AgentId id, std::uint64_t seq, std::int64_t incarnation, double x = 0.0) {
  StateMessage m;
  m.view.id = id;
  m.seq = seq;
  m.incarnation = incarnation;
  m.view.q = Vec3(x, 0, 0);
  m.phase = Phase::kRunning;
  return m;
}

struct Feed {
  SampleGate gate;
  std::int64_t now = kNow;
  SampleGate::Result admit(const StateMessage& m, const WriterId& w) {
    now += 20 * kMs;  // 50 Hz
    return gate.admit(m, check_message(m), now, w);
  }
  double held_x(AgentId id) const {
    double x = -1.0;
    gate.for_each_latest(0, [&](const StateMessage& m) {
      if (m.view.id == id) x = m.view.q.x();
    });
    return x;
  }
  std::uint8_t suspected(AgentId id) const {
    const auto it = gate.suspects().find(id);
    return it == gate.suspects().end() ? 0 : it->second;
  }
};

constexpr std::int64_t kLife = kNow - 5'000'000'000;  // the real agent started 5 s ago

TEST(SampleGate, EachHeldAgentIsVisitedOnceInIdOrderButItsOwn) {
  Feed f;
  f.admit(sample(3, 1, kLife, 3.0), writer(3));
  f.admit(sample(2, 1, kLife, 2.0), writer(2));
  f.admit(sample(2, 2, kLife, 2.5), writer(2));
  f.admit(sample(1, 1, kLife, 1.0), writer(1));
  std::vector<std::pair<AgentId, double>> seen;
  f.gate.for_each_latest(
      1, [&](const StateMessage& m) { seen.emplace_back(m.view.id, m.view.q.x()); });
  EXPECT_EQ(seen, (std::vector<std::pair<AgentId, double>>{{2, 2.5}, {3, 3.0}}));
}

TEST(SampleGate, CountsTheArrivalAgesOfAcceptedSamplesThatCarryAWallTime) {
  SampleGate gate;
  const auto at = [&](AgentId id, std::uint64_t seq, std::int64_t sent_ns, std::int64_t now_ns) {
    StateMessage m = sample(id, seq, kLife);
    m.wall_ns = sent_ns;
    return gate.admit(m, check_message(m), now_ns, writer(static_cast<std::uint8_t>(id)));
  };
  // 98 samples 1 ms old, one 3 ms old, one 250 ms old
  for (std::uint64_t k = 1; k <= 98; ++k) at(1, k, kNow + k * 20 * kMs, kNow + k * 20 * kMs + kMs);
  at(2, 1, kNow, kNow + 3 * kMs);
  at(2, 2, kNow, kNow + 250 * kMs);
  // refused (stale), without a wall time, or without the receiver's: not counted
  at(2, 2, kNow, kNow + 900 * kMs);
  at(3, 1, 0, kNow);
  at(3, 2, kNow, 0);
  const ArrivalAges& a = gate.counters().ages;
  EXPECT_EQ(a.total(), 100u);
  // a bin's upper edge: at most 19 % above the true value, never below it
  EXPECT_GE(a.quantile_ms(0.5), 1.0);
  EXPECT_LT(a.quantile_ms(0.5), 1.19);
  EXPECT_GE(a.quantile_ms(0.99), 3.0);
  EXPECT_LT(a.quantile_ms(0.99), 3.57);
  EXPECT_GE(a.quantile_ms(1.0), 250.0);
  EXPECT_LT(a.quantile_ms(1.0), 297.5);
  EXPECT_EQ(ArrivalAges{}.quantile_ms(0.5), -1.0);
}

TEST(SampleGate, ArrivalAgesOutsideTheBinsAreCountedApartOrInTheOpenLastBin) {
  ArrivalAges a;
  a.add(-5 * kMs);  // stamped after it arrived (a clock stepped back, a forged stamp): apart
  a.add(0);
  a.add(3'600'000 * kMs);  // an hour: the last bin, whose upper edge is open
  a.add(std::numeric_limits<std::int64_t>::max());
  EXPECT_EQ(a.early, 1u);
  EXPECT_EQ(a.total(), 3u);
  EXPECT_EQ(a.count.front(), 1u);
  EXPECT_EQ(a.count.back(), 2u);
  EXPECT_DOUBLE_EQ(a.quantile_ms(0.3), 0.01);
  EXPECT_EQ(a.quantile_ms(0.99), std::numeric_limits<double>::infinity());
  EXPECT_EQ(a.quantile_ms(std::nan("")), -1.0);
}

TEST(SampleGate, AnImpersonatorBesideTheRealAgentIsNamedAndRefusedWhileTheRealOneSpeaks) {
  Feed f;
  const WriterId real = writer(1), forger = writer(2);
  for (std::uint64_t k = 1; k <= 5; ++k) f.admit(sample(3, k, kLife, 1.0), real);
  // The forger claims a newer life and larger numbers, interleaved with the real samples.
  int refused = 0;
  for (std::uint64_t k = 6; k <= 20; ++k) {
    EXPECT_EQ(f.admit(sample(3, k, kLife, 1.0), real).verdict, SampleGate::Verdict::kAccepted);
    refused +=
        f.admit(sample(3, 1000 + k, kNow, 99.0), forger).verdict == SampleGate::Verdict::kContested
            ? 1
            : 0;
    EXPECT_EQ(f.held_x(3), 1.0) << "at " << k;
  }
  EXPECT_EQ(refused, 15);
  EXPECT_EQ(f.suspected(3), kTwoWriters);
  EXPECT_EQ(f.gate.counters().contested, 15u);
}

TEST(SampleGate, AForgerThatOutpacesTheRealAgentTakesItOverButTheRealOneIsHeardOnceItStops) {
  Feed f;
  const WriterId real = writer(1), forger = writer(2);
  std::uint64_t seq = 1;
  for (; seq <= 5; ++seq) f.admit(sample(3, seq, kLife, 1.0), real);
  // Four forged samples for every real one: the real writer is silent long enough to lose it.
  const std::int64_t forged_life = kNow + 50'000'000'000;  // 50 s ahead: under the skew limit
  for (int round = 0; round < 10; ++round) {
    for (int k = 0; k < 4; ++k)
      f.admit(sample(3, 1'000'000 + static_cast<std::uint64_t>(round * 4 + k), forged_life, 99.0),
              forger);
    f.admit(sample(3, seq++, kLife, 1.0), real);
  }
  EXPECT_EQ(f.held_x(3), 99.0);  // the forger holds it now
  EXPECT_TRUE(f.suspected(3) & kTwoWriters);
  // The forger stops: its "newer" life and numbers do not lock the real agent out. The real
  // writer spoke last, so fewer than kTakeover more of its samples take the agent back.
  int more = 0;
  while (more < SampleGate::kTakeover && !f.admit(sample(3, seq++, kLife, 1.0), real).new_owner)
    ++more;
  EXPECT_LT(more, SampleGate::kTakeover);
  EXPECT_EQ(f.held_x(3), 1.0);
  EXPECT_EQ(f.admit(sample(3, seq++, kLife, 2.0), real).verdict, SampleGate::Verdict::kAccepted);
  EXPECT_EQ(f.held_x(3), 2.0);
}

TEST(SampleGate, ARelayOfTheRealSamplesWithAHigherSequenceIsAJumpAndTwoWriters) {
  Feed f;
  const WriterId real = writer(1), relay = writer(2);
  for (std::uint64_t k = 1; k <= 30; ++k) {
    f.admit(sample(1, k, kLife, 1.0), real);
    // The relay: the same sample, one million ahead, its flows shifted.
    EXPECT_NE(f.admit(sample(1, k + 1'000'000, kLife, 51.0), relay).verdict,
              SampleGate::Verdict::kAccepted);
  }
  EXPECT_EQ(f.held_x(1), 1.0);
  EXPECT_EQ(f.suspected(1), kTwoWriters | kSequenceJump);
}

TEST(SampleGate, ARelayHeardBeforeTheRealAgentLosesItToTheRealAgentsFirstSample) {
  // Discovery may match the relay's writer before the real agent's: the relay owns agent 1 first.
  Feed f;
  const WriterId real = writer(1), relay = writer(2);
  f.admit(sample(1, 1'000'001, kLife, 51.0), relay);
  f.admit(sample(1, 1'000'002, kLife, 51.0), relay);
  EXPECT_EQ(f.held_x(1), 51.0);
  // Its numbers are a jump ahead of the real agent's in the same life: it forged them.
  const SampleGate::Result r = f.admit(sample(1, 3, kLife, 1.0), real);
  EXPECT_EQ(r.verdict, SampleGate::Verdict::kAccepted);
  EXPECT_TRUE(r.new_owner);
  for (std::uint64_t k = 4; k <= 20; ++k) {
    f.admit(sample(1, 1'000'000 + k, kLife, 51.0), relay);
    f.admit(sample(1, k, kLife, 1.0), real);
    EXPECT_EQ(f.held_x(1), 1.0) << "at " << k;
  }
  EXPECT_EQ(f.suspected(1), kTwoWriters | kSequenceJump);
}

TEST(SampleGate, TwoWritersAreNamedWhenOneSpeaksTwentyTimesAsOftenAndWhenThreeTakeTurns) {
  Feed fast;
  for (std::uint64_t k = 1; k <= 4; ++k) {
    fast.admit(sample(2, k, kLife, 1.0), writer(1));
    for (std::uint64_t j = 0; j < 20; ++j) fast.admit(sample(2, 100 * k + j, kNow, 9.0), writer(2));
  }
  EXPECT_TRUE(fast.suspected(2) & kTwoWriters);
  Feed turns;
  for (std::uint64_t k = 1; k <= 4; ++k)
    for (std::uint8_t w = 1; w <= 3; ++w) turns.admit(sample(2, k, kLife, 1.0), writer(w));
  EXPECT_TRUE(turns.suspected(2) & kTwoWriters);
}

TEST(SampleGate, AForgerRotatingMoreWritersThanTheGateRemembersIsStillTwoWriters) {
  // Three samples of its main writer, four of others (as many as the gate remembers), then the
  // real agent's: without the owner's place kept, the real one is forgotten before it returns.
  Feed f;
  const WriterId real = writer(1), forger = writer(2);
  std::uint64_t seq = 1, forged = 1'000'000;
  for (; seq <= 5; ++seq) f.admit(sample(3, seq, kLife, 1.0), real);
  for (int round = 0; round < 10; ++round) {
    for (int k = 0; k < 3; ++k) f.admit(sample(3, forged++, kLife, 99.0), forger);
    for (std::uint8_t x = 10; x < 14; ++x) f.admit(sample(3, forged++, kLife, 99.0), writer(x));
    f.admit(sample(3, seq++, kLife, 1.0), real);
  }
  EXPECT_TRUE(f.suspected(3) & kTwoWriters);
}

TEST(SampleGate, AForgerAtHalfTheRateWithSmallNumbersInTheRealLifeNeverTakesTheAgent) {
  // The real agent has flown ten minutes (30000 samples): a forger replaying its life from
  // sequence 1 is far behind it, but the real numbers are ones its life could have reached.
  Feed f;
  const WriterId real = writer(1), forger = writer(2);
  const std::int64_t life = kNow - 600'000'000'000;
  std::uint64_t seq = 30'000, forged = 1;
  for (int k = 0; k < 5; ++k) f.admit(sample(3, seq++, life, 1.0), real);
  for (int round = 0; round < 30; ++round) {
    f.admit(sample(3, seq++, life, 1.0), real);
    f.admit(sample(3, seq++, life, 1.0), real);
    EXPECT_EQ(f.admit(sample(3, forged++, life, 99.0), forger).verdict,
              SampleGate::Verdict::kContested)
        << "round " << round;
    EXPECT_EQ(f.held_x(3), 1.0) << "round " << round;
  }
  EXPECT_TRUE(f.suspected(3) & kTwoWriters);
}

TEST(SampleGate, AJumpFromTheOwnersOwnWriterIsRefusedAndItsNextSampleIsNot) {
  // A forger that spoofs the real writer's identity (plain RTPS cannot tell) with a large number.
  Feed f;
  const WriterId real = writer(1);
  for (std::uint64_t k = 1; k <= 5; ++k) f.admit(sample(2, k, kLife, 1.0), real);
  EXPECT_EQ(f.admit(sample(2, 5'000'000, kLife, 99.0), real).verdict,
            SampleGate::Verdict::kContested);
  EXPECT_EQ(f.suspected(2), kSequenceJump);
  EXPECT_EQ(f.admit(sample(2, 6, kLife, 2.0), real).verdict, SampleGate::Verdict::kAccepted);
  EXPECT_EQ(f.held_x(2), 2.0);
}

TEST(SampleGate, ARestartIsANewWriterHeardAfterAFewSamplesAndNamesNothing) {
  Feed f;
  const WriterId first_life = writer(1), second_life = writer(2), third_life = writer(3);
  for (std::uint64_t k = 1; k <= 50; ++k) f.admit(sample(4, k, kLife, 1.0), first_life);
  // Killed; restarted with a new writer, a newer life and numbers from 1.
  SampleGate::Result r;
  for (std::uint64_t k = 1; k <= SampleGate::kTakeover; ++k)
    r = f.admit(sample(4, k, kLife + 10'000'000'000, 2.0), second_life);
  EXPECT_TRUE(r.new_owner);
  EXPECT_EQ(f.held_x(4), 2.0);
  for (std::uint64_t k = 4; k <= 10; ++k)
    EXPECT_EQ(f.admit(sample(4, k, kLife + 10'000'000'000, 2.0), second_life).verdict,
              SampleGate::Verdict::kAccepted);
  // And again.
  for (std::uint64_t k = 1; k <= 10; ++k)
    f.admit(sample(4, k, kLife + 20'000'000'000, 3.0), third_life);
  EXPECT_EQ(f.held_x(4), 3.0);
  EXPECT_TRUE(f.gate.suspects().empty());
}

TEST(SampleGate, AnIncarnationFromTheFutureIsRefusedAndNamed) {
  Feed f;
  f.admit(sample(5, 1, kLife, 1.0), writer(1));
  const SampleGate::Result r = f.admit(sample(5, 2, kNow + 3'600'000'000'000, 9.0), writer(2));
  EXPECT_EQ(r.verdict, SampleGate::Verdict::kInvalid);
  EXPECT_EQ(r.noticed, kFutureIncarnation);
  EXPECT_EQ(f.suspected(5), kFutureIncarnation);
  EXPECT_EQ(f.held_x(5), 1.0);
}

TEST(SampleGate, WithoutWritersKnownANewerLifeTakesOverAtOnceAsBefore) {
  // The in-memory bus knows no writers: one writer per agent, ordered by life and sequence.
  SampleGate gate;
  EXPECT_EQ(gate.admit(sample(6, 10, 100), "").verdict, SampleGate::Verdict::kAccepted);
  EXPECT_EQ(gate.admit(sample(6, 9, 100), "").verdict, SampleGate::Verdict::kStale);
  EXPECT_EQ(gate.admit(sample(6, 1, 200), "").verdict, SampleGate::Verdict::kAccepted);
  EXPECT_TRUE(gate.suspects().empty());
}

}  // namespace
}  // namespace qswarm

namespace qswarm {
namespace {

TEST(SampleGate, ASampleOfAnotherLawOrWithALongerPayloadNeverReachesTheLaw) {
  Feed f{SampleGate(0, {law_tag("metropolis"), 1})};
  StateMessage ok = sample(3, 1, kLife, 1.0);
  ok.view.law = law_tag("metropolis");
  ok.view.payload = {2.0};
  EXPECT_EQ(f.admit(ok, writer(3)).verdict, SampleGate::Verdict::kAccepted);
  StateMessage other = sample(3, 2, kLife, 50.0);
  other.view.law = law_tag("edge-flow");
  SampleGate::Result r = f.admit(other, writer(3));
  EXPECT_EQ(r.verdict, SampleGate::Verdict::kInvalid);
  EXPECT_EQ(r.why, "a sample of another law");
  EXPECT_TRUE(r.first_from);  // named once
  StateMessage longer = sample(3, 3, kLife, 60.0);
  longer.view.law = law_tag("metropolis");
  longer.view.payload = {2.0, 7.0};
  r = f.admit(longer, writer(3));
  EXPECT_EQ(r.verdict, SampleGate::Verdict::kInvalid);
  EXPECT_EQ(r.why, "law payload longer than the law's bound");
  EXPECT_FALSE(r.first_from);  // counted, not named again
  StateMessage nan = sample(3, 4, kLife, 70.0);
  nan.view.law = law_tag("metropolis");
  nan.view.payload = {std::nan("")};
  EXPECT_EQ(f.admit(nan, writer(3)).why, "law payload not finite or absurd");
  EXPECT_EQ(f.gate.counters().dropped, 3u);
  EXPECT_EQ(f.held_x(3), 1.0);  // the law still reads the last good sample
  // A gate that expects no law (tag 0) checks only the wire's bounds.
  Feed any;
  EXPECT_EQ(any.admit(other, writer(3)).verdict, SampleGate::Verdict::kAccepted);
}

}  // namespace
}  // namespace qswarm
