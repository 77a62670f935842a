// The id claim as swarm-agent runs it (IdClaimRunner over a claim bus), with every replica in one
// process on one manual clock: what compose's replicas do over DDS, deterministic and in
// milliseconds.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <memory>
#include <numeric>
#include <random>
#include <set>

#include "common/claim/claim_runner.hpp"
#include "tests/support/plan_for.hpp"

namespace qswarm {
namespace {

constexpr std::uint64_t kRun = 0x51;

struct Replica {
  std::unique_ptr<InMemoryClaimBus> bus;
  std::unique_ptr<IdClaimRunner> runner;
  double start_s = 0.0;
  AgentId fixed = 0;
  AgentId taken = 0;
  bool refused = false;
  std::string why;
};

// `n` replicas told the swarm's size `size`, stepping every 20 ms of simulated time.
class Swarm {
 public:
  explicit Swarm(int size) : size_(size) {}
  void add(double start_s, AgentId fixed = 0) {
    replicas_.push_back({nullptr, nullptr, start_s, fixed, 0, false, {}});
  }
  void run_until(double t_end) {
    std::vector<AgentId> roster(static_cast<std::size_t>(size_));
    std::iota(roster.begin(), roster.end(), AgentId{1});
    for (; clock_.now_s() <= t_end; clock_.advance(0.02)) {
      for (Replica& r : replicas_) {
        if (r.refused || clock_.now_s() < r.start_s) continue;
        if (!r.runner) {  // the replica's process starts now
          const RunPlan plan = test::plan_for(static_cast<std::size_t>(size_));
          r.bus = std::make_unique<InMemoryClaimBus>(net_, kRun, plan.claim_capacity);
          r.runner = std::make_unique<IdClaimRunner>(
              *r.bus, roster, kRun, r.fixed,
              IdClaimer::Config::with_period(plan.claim_period_s, plan.claim_timeout_s), rng_(),
              clock_);
        }
        if (r.taken) {  // flying: keeps its claim up, and yields only to an earlier flight
          if (const auto why = r.runner->keep()) stop(r, *why);
          continue;
        }
        const IdClaimer::Step s = r.runner->poll();
        if (s.refuse) stop(r, s.message);
        if (s.taken) r.taken = s.taken;
      }
      net_.deliver();
    }
  }
  const std::vector<Replica>& replicas() const { return replicas_; }
  InMemoryClaimNetwork& network() { return net_; }

 private:
  void stop(Replica& r, const std::string& why) {
    r.refused = true;
    r.why = why;
    r.runner.reset();  // the process exits: it falls silent
    r.bus.reset();
  }
  int size_;
  ManualClock clock_;
  InMemoryClaimNetwork net_;
  std::mt19937_64 rng_{20261123};
  std::vector<Replica> replicas_;
};

TEST(ClaimRunner, ThirtyTwoReplicasALateOneAndTwoTooManyFlyEveryIdExactlyOnce) {
  // Given 31 replicas at once, the 32nd 20 s later, then one replica too many and one given an id
  // that is already flown
  Swarm swarm(32);
  for (int i = 0; i < 31; ++i) swarm.add(0.0);
  swarm.add(20.0);
  swarm.add(120.0);     // one too many: ranked past the free ids
  swarm.add(125.0, 7);  // --id 7 --claim while agent 7 flies
  // When they claim over the in-memory claim bus
  swarm.run_until(200.0);
  // Then the 32 fly the ids 1..32, each once, and the two extra replicas are refused saying why
  std::vector<AgentId> flown;
  for (std::size_t i = 0; i < 32; ++i) {
    const Replica& r = swarm.replicas()[i];
    EXPECT_FALSE(r.refused) << "replica " << i << ": " << r.why;
    flown.push_back(r.taken);
  }
  std::sort(flown.begin(), flown.end());
  std::vector<AgentId> all(32);
  std::iota(all.begin(), all.end(), AgentId{1});
  EXPECT_EQ(flown, all);
  const Replica& extra = swarm.replicas()[32];
  EXPECT_TRUE(extra.refused);
  EXPECT_EQ(extra.taken, 0u);
  EXPECT_NE(extra.why.find("32"), std::string::npos) << extra.why;
  const Replica& dup = swarm.replicas()[33];
  EXPECT_TRUE(dup.refused);
  EXPECT_EQ(dup.taken, 0u);
  EXPECT_NE(dup.why.find("7"), std::string::npos) << dup.why;
}

TEST(ClaimInbox, AFloodOfNoncesStaysBoundedAndDoesNotHideALaterReplica) {
  // Given an inbox for a swarm of 4 (2 x 4 + 16 claims) and a stranger who floods 200 nonces once
  ClaimInbox inbox(kRun, test::plan_for(4).claim_capacity);
  bool logged = false;
  for (std::uint64_t n = 1000; n < 1200; ++n)
    logged |= inbox.hear(IdClaim{n, 1, kRun, 4, 0, kRanking, 0.0});
  EXPECT_TRUE(logged);  // the first eviction is worth a log line
  EXPECT_EQ(inbox.claims().size(), 24u);
  // When a replica is heard afterwards
  inbox.hear(IdClaim{7, 1, kRun, 4, 0, kRanking, 0.0});
  // Then it is kept, the inbox stays bounded, and another run's claims are not kept at all
  const std::vector<IdClaim> heard = inbox.claims();
  EXPECT_EQ(heard.size(), 24u);
  EXPECT_TRUE(
      std::any_of(heard.begin(), heard.end(), [](const IdClaim& c) { return c.nonce == 7; }));
  EXPECT_FALSE(inbox.hear(IdClaim{8, 1, kRun + 1, 4, 0, kRanking, 0.0}));
  const std::vector<IdClaim> after = inbox.claims();
  EXPECT_FALSE(
      std::any_of(after.begin(), after.end(), [](const IdClaim& c) { return c.nonce == 8; }));
  EXPECT_EQ(inbox.evicted(), 177u);  // 200 + 1 - 24
}

}  // namespace
}  // namespace qswarm
