// The id claim (swarm-agent --id auto): replicas started alike end up flying distinct ids, and no
// id is ever held by two live replicas for longer than one exchange.
#include <gtest/gtest.h>

#include <map>
#include <memory>
#include <numeric>
#include <optional>
#include <random>
#include <set>

#include "common/claim/id_claimer.hpp"
#include "tests/support/plan_for.hpp"

namespace qswarm {
namespace {

std::vector<AgentId> roster(int n) {
  std::vector<AgentId> r(static_cast<std::size_t>(n));
  std::iota(r.begin(), r.end(), AgentId{1});
  return r;
}

// Replicas exchanging claims every 20 ms of simulated wall time; each hears every other's latest
// claim (a replica joins the exchange at its start time).
struct Replicas {
  struct R {
    IdClaimer claimer;
    double start_s;
    bool started = false;
    bool refused = false;
    std::string why;
    AgentId taken = 0;
    double deaf_until_s = 0.0;  // hears nothing before this (slow discovery)
  };
  std::vector<R> rs;
  std::map<std::uint64_t, IdClaim> wire;
  double now = 0.0;

  void add(std::uint64_t nonce, int n, AgentId fixed = 0, double start_s = 0.0,
           double timeout_s = 120.0) {
    IdClaimer::Config c;
    c.timeout_s = timeout_s;
    rs.push_back(
        {IdClaimer(roster(n), nonce, 7, fixed, c, start_s), start_s, false, false, {}, 0, 0.0});
  }
  void run_until(double t_end) {
    for (; now <= t_end; now += 0.02) {
      std::vector<IdClaim> heard;
      for (const auto& [nonce, c] : wire) heard.push_back(c);
      for (R& r : rs) {
        if (now < r.start_s || r.refused) continue;
        const IdClaimer::Step s =
            r.claimer.step(now, now < r.deaf_until_s ? std::vector<IdClaim>{} : heard);
        if (s.announce) wire[r.claimer.claim().nonce] = r.claimer.claim();
        if (s.taken) r.taken = s.taken;
        if (s.refuse) {
          r.refused = true;
          r.why = s.message;
          wire.erase(r.claimer.claim().nonce);  // the process exits: it falls silent
        }
      }
    }
  }
  std::vector<AgentId> flying() const {
    std::vector<AgentId> ids;
    for (const R& r : rs)
      if (!r.refused && r.taken) ids.push_back(r.taken);
    std::sort(ids.begin(), ids.end());
    return ids;
  }
};

TEST(IdClaimer, ReplicasStartedAlikeTakeEveryIdOnce) {
  std::mt19937_64 rng(42);
  for (int n : {1, 2, 8, 32}) {
    Replicas net;
    for (int k = 0; k < n; ++k) net.add(rng() | 1, n, 0, 0.05 * k);  // staggered starts
    net.run_until(10.0);
    EXPECT_EQ(net.flying(), roster(n)) << "n=" << n;
  }
}

TEST(IdClaimer, OneReplicaTooManyIsLeftWithoutAnIdAndTheRestFly) {
  Replicas net;
  for (std::uint64_t k = 1; k <= 9; ++k) net.add(k * 1000, 8);
  net.run_until(10.0);
  EXPECT_EQ(net.flying(), roster(8));
  int refused = 0;
  for (const auto& r : net.rs) {
    if (!r.refused) continue;
    ++refused;
    EXPECT_EQ(r.claimer.claim().nonce, 9000u);  // the largest nonce is ranked past the ids
    EXPECT_NE(r.why.find("more replicas than the swarm's 8 agents"), std::string::npos) << r.why;
  }
  EXPECT_EQ(refused, 1);
}

TEST(IdClaimer, ALateReplicaTakesTheIdNobodyHolds) {
  Replicas net;
  for (std::uint64_t k = 1; k <= 4; ++k) net.add(k, 5);
  net.run_until(3.0);
  EXPECT_TRUE(net.flying().empty());  // 4 of 5: nobody takes an id yet
  net.add(999, 5, 0, 3.0);
  net.run_until(8.0);
  EXPECT_EQ(net.flying(), roster(5));
}

TEST(IdClaimer, ReplicasToldDifferentSizesRefuse) {
  Replicas net;
  net.add(1, 3);
  net.add(2, 3);
  net.add(3, 4);
  net.run_until(3.0);
  EXPECT_TRUE(net.flying().empty());
  for (const auto& r : net.rs) {
    EXPECT_TRUE(r.refused);
    EXPECT_NE(r.why.find("same swarm size"), std::string::npos) << r.why;
  }
}

TEST(IdClaimer, AnIdGivenTwiceIsFlownOnceAndAutoReplicasLeaveItAlone) {
  // Two replicas given --id 2 and one auto replica, together: the auto one takes 1 (2 is given),
  // both given ones confirm 2, the larger nonce refuses before either flies.
  Replicas net;
  net.add(50, 3, 2);
  net.add(60, 3, 2);
  net.add(5, 3);
  net.run_until(4.0);
  EXPECT_EQ(net.flying(), (std::vector<AgentId>{1, 2}));
  EXPECT_FALSE(net.rs[0].refused);
  EXPECT_TRUE(net.rs[1].refused);
  EXPECT_EQ(net.rs[1].taken, 0u);
  EXPECT_NE(net.rs[1].why.find("agent id 2 is already held by another replica"), std::string::npos)
      << net.rs[1].why;
  // A replica given 2 later finds it flown and refuses before taking it; one given 3 flies it.
  net.add(10, 3, 2, 4.0);
  net.add(11, 3, 3, 4.0);
  net.run_until(8.0);
  EXPECT_TRUE(net.rs[3].refused);
  EXPECT_EQ(net.rs[3].taken, 0u);
  EXPECT_NE(net.rs[3].why.find("already held"), std::string::npos) << net.rs[3].why;
  EXPECT_EQ(net.flying(), (std::vector<AgentId>{1, 2, 3}));
}

TEST(IdClaimer, AGivenIdWaitsForTheSwarmSoADeafNewcomerNeverFliesIt) {
  Replicas net;
  net.add(100, 3, 2);
  net.add(200, 3);
  net.add(300, 3);
  net.run_until(3.0);
  ASSERT_EQ(net.flying(), (std::vector<AgentId>{1, 2, 3}));
  // A newcomer given 2, with a smaller nonce, that discovers nobody for 3 s: it does not confirm
  // alone, and refuses once it hears the flyer.
  net.add(1, 3, 2, 3.0);
  net.rs[3].deaf_until_s = 6.0;
  net.run_until(9.0);
  EXPECT_TRUE(net.rs[3].refused);
  EXPECT_EQ(net.rs[3].taken, 0u);
  EXPECT_EQ(net.flying(), (std::vector<AgentId>{1, 2, 3}));
}

TEST(IdClaimer, OfTwoFlightsOfOneIdTheEarlierKeepsIt) {
  // A flies 1 (alone, N = 1); then it hears another replica flying 1 too: a later flight does not
  // make it yield, whatever the nonces; an earlier one does.
  const auto flying = [] {
    auto c = std::make_unique<IdClaimer>(roster(1), 50, 7, 0, IdClaimer::Config{}, 0.0);
    for (double t = 0.0; t < 5.0; t += 0.02) c->step(t, {});
    return c;
  };
  auto a = flying();
  ASSERT_EQ(a->claim().stage, kFlying);
  IdClaim later{1, 1, 7, 1, 1, kFlying, 0.5};  // smaller nonce, but flying for 0.5 s only
  for (int k = 0; k < 10; ++k) {
    later.seq++;
    EXPECT_FALSE(a->step(5.0 + 0.1 * k, {later}).refuse);
  }
  auto b = flying();
  const IdClaim earlier{999, 1, 7, 1, 1, kFlying, 30.0};  // larger nonce, flying for 30 s
  const IdClaimer::Step s = b->step(5.0, {earlier});
  EXPECT_TRUE(s.refuse);
  EXPECT_NE(s.message.find("flew it first"), std::string::npos) << s.message;
}

TEST(IdClaimer, AStrayReplicaToldAnotherSizeDoesNotStopAFlyingSwarm) {
  Replicas net;
  for (std::uint64_t k = 1; k <= 3; ++k) net.add(k * 10, 3);
  net.run_until(3.0);
  ASSERT_EQ(net.flying(), roster(3));
  net.add(7, 4, 0, 3.0);
  net.run_until(6.0);
  EXPECT_EQ(net.flying(), roster(3));
  EXPECT_TRUE(net.rs[3].refused);
  EXPECT_NE(net.rs[3].why.find("same swarm size"), std::string::npos) << net.rs[3].why;
}

TEST(IdClaimer, NothingIsDecidedBeforeEveryMatchedWriterIsHeard) {
  // DDS matched a second claim writer whose claims have not arrived: the replica waits.
  IdClaimer c(roster(1), 5, 7, 0, IdClaimer::Config{}, 0.0);
  for (double t = 0.0; t < 10.0; t += 0.02) EXPECT_EQ(c.step(t, {}, 2).taken, 0u);
  AgentId taken = 0;
  for (double t = 10.0; t < 15.0 && !taken; t += 0.02) taken = c.step(t, {}, 1).taken;
  EXPECT_EQ(taken, 1u);
}

TEST(IdClaimer, ABigSwarmClaimsLessOftenWithWindowsToMatch) {
  const RunPlan four = test::plan_for(4);
  const IdClaimer::Config few =
      IdClaimer::Config::with_period(four.claim_period_s, four.claim_timeout_s);
  EXPECT_DOUBLE_EQ(few.period_s, 0.1);
  EXPECT_DOUBLE_EQ(few.expire_s, 2.0);
  EXPECT_DOUBLE_EQ(few.timeout_s, 76.0);
  const IdClaimer::Config many =
      IdClaimer::Config::with_period(test::plan_for(32).claim_period_s, 30.0);
  EXPECT_NEAR(many.period_s, 0.1 * 32 / 6, 1e-12);
  EXPECT_NEAR(many.expire_s, 15 * many.period_s, 1e-12);
  EXPECT_NEAR(many.settle_s, 3 * many.period_s, 1e-12);
  EXPECT_NEAR(many.confirm_s, 3 * many.period_s, 1e-12);
  EXPECT_DOUBLE_EQ(many.timeout_s, 30.0);
}

TEST(IdClaimer, TooFewReplicasTimeOutWithAMessage) {
  Replicas net;
  for (std::uint64_t k = 1; k <= 5; ++k) net.add(k, 8, 0, 0.0, 5.0);
  net.run_until(6.0);
  EXPECT_TRUE(net.flying().empty());
  for (const auto& r : net.rs) {
    EXPECT_TRUE(r.refused);
    EXPECT_NE(r.why.find("heard 5 of 8 replicas"), std::string::npos) << r.why;
  }
}

TEST(IdClaimer, ForgetsReplicasTheBusNoLongerReportsOnceTheyFellSilent) {
  // Hundreds of replicas come and go (restarts, strangers): what the claimer remembers is bounded
  // by what the bus reports, and a departed replica still counts until it expires.
  IdClaimer::Config cfg;
  IdClaimer c(roster(4), 1, 7, 0, cfg, 0.0);
  double now = 0.0;
  for (std::uint64_t wave = 0; wave < 50; ++wave) {
    std::vector<IdClaim> heard;
    for (std::uint64_t k = 0; k < 8; ++k) {
      IdClaim claim;
      claim.nonce = 100 + wave * 8 + k;
      claim.seq = 1;
      claim.run_id = 7;
      claim.expected = 4;
      heard.push_back(claim);
    }
    c.step(now, heard);
    EXPECT_EQ(c.live(), 9u);  // this wave is live
    now += cfg.expire_s / 2.0;
    c.step(now, {});  // the bus forgot them: still live until they expire
    EXPECT_EQ(c.live(), 9u);
    now += cfg.expire_s;
    c.step(now, {});
    EXPECT_EQ(c.live(), 1u);
    EXPECT_EQ(c.remembered(), 0u);
  }
  // A nonce the bus still reports is remembered (its next claim is told apart from the last).
  IdClaim kept;
  kept.nonce = 5;
  kept.seq = 3;
  kept.run_id = 7;
  kept.expected = 4;
  c.step(now, {kept});
  now += 2.0 * cfg.expire_s;
  c.step(now, {kept});
  EXPECT_EQ(c.live(), 1u);
  EXPECT_EQ(c.remembered(), 1u);
  kept.seq = 4;
  c.step(now, {kept});
  EXPECT_EQ(c.live(), 2u);
}

TEST(IdClaimer, AReplacementTakesTheIdOfAReplicaThatDiedBeforeTakingIt) {
  // Three of three rank; one dies before taking its id: the other two take theirs (it was still
  // live when the view settled), its id stays free, and a replacement replica takes it.
  Replicas net;
  net.add(1, 3);
  net.add(2, 3);
  net.add(3, 3);
  net.run_until(0.5);
  net.rs[2].refused = true;  // killed
  net.wire.erase(3);
  net.run_until(4.0);
  EXPECT_EQ(net.flying(), (std::vector<AgentId>{1, 2}));
  net.add(4, 3, 0, 4.0);
  net.run_until(8.0);
  EXPECT_EQ(net.flying(), roster(3));
}

}  // namespace
}  // namespace qswarm

namespace qswarm {
namespace {

// Compose at 32 on two saturated cores: podman-compose starts one container a second, and a
// starved replica runs its claim loop late (gaps of 0.1 to 0.5 s, and now and then a stall of 2 to
// 5 s); its claims reach the others up to 0.4 s late. Every replica must still take a distinct
// id, and no id may be confirmed by two replicas.
TEST(IdClaimer, ThirtyTwoStarvedReplicasStartedOneASecondStillTakeEveryIdOnce) {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    const int n = 32;
    const RunPlan plan = test::plan_for(n);
    const IdClaimer::Config cfg =
        IdClaimer::Config::with_period(plan.claim_period_s, plan.claim_timeout_s);
    struct R {
      std::optional<IdClaimer> claimer;
      double start_s, next_s;
      AgentId taken = 0;
      bool refused = false;
      std::string why;
    };
    std::vector<R> rs;
    rs.reserve(n);
    for (int k = 0; k < n; ++k) rs.push_back({std::nullopt, 1.0 * k, 1.0 * k, 0, false, {}});
    std::map<std::uint64_t, IdClaim> wire;  // what has arrived
    std::vector<std::pair<double, IdClaim>> in_flight;
    std::map<AgentId, int> confirmed;
    for (double now = 0.0; now < cfg.timeout_s + 40.0; now += 0.01) {
      for (auto it = in_flight.begin(); it != in_flight.end();) {
        if (it->first <= now) {
          wire[it->second.nonce] = it->second;
          it = in_flight.erase(it);
        } else {
          ++it;
        }
      }
      std::vector<IdClaim> heard;
      heard.reserve(wire.size());
      for (const auto& [nonce, c] : wire) heard.push_back(c);
      for (R& r : rs) {
        if (now < r.next_s || r.refused) continue;
        if (!r.claimer) r.claimer.emplace(roster(n), rng() | 1, 7, 0, cfg, now);
        const IdClaimer::Step s = r.claimer->step(now, heard);
        if (s.announce) in_flight.emplace_back(now + 0.4 * u01(rng), r.claimer->claim());
        if (s.taken) {
          r.taken = s.taken;
          ++confirmed[s.taken];
        }
        if (s.refuse) {
          r.refused = true;
          r.why = s.message;
        }
        r.next_s = now + (u01(rng) < 0.03 ? 2.0 + 3.0 * u01(rng) : 0.1 + 0.4 * u01(rng));
      }
    }
    std::vector<AgentId> ids;
    for (const R& r : rs) {
      EXPECT_FALSE(r.refused) << "seed " << seed << ": " << r.why;
      if (r.taken) ids.push_back(r.taken);
    }
    std::sort(ids.begin(), ids.end());
    EXPECT_EQ(ids, roster(n)) << "seed " << seed;
    // The progress line a claiming replica logs every 10 s says where it stands.
    const std::string st = rs[0].claimer->status(cfg.timeout_s + 40.0, 32);
    EXPECT_NE(st.find("of 32 replicas"), std::string::npos) << st;
    EXPECT_NE(st.find("32 claim writers matched"), std::string::npos) << st;
    for (const auto& [id, times] : confirmed)
      EXPECT_EQ(times, 1) << "seed " << seed << " id " << id;
  }
}

}  // namespace
}  // namespace qswarm
