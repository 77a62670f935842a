// The id-claim topic over real DDS participants: the claims a bus keeps are bounded, and a
// stranger flooding nonces cannot freeze them (the one heard longest ago goes).
#include <gtest/gtest.h>

#include <algorithm>

#include "common/dds/dds_bus.hpp"
#include "tests/swarm/domain_lease.hpp"
#include "tests/swarm/harness.hpp"

namespace qswarm {
namespace {

DdsOptions options(const char* name) {
  DdsOptions o;
  o.participant.domain_id = static_cast<std::uint32_t>(test::test_domain().domain());
  o.participant.name = name;
  o.state.max_agents = 4;
  o.claims_kept = 24;  // a swarm of 4's (RunPlan::claim_capacity: 2 * 4 + 16)
  o.state.run_id = 0xC1;
  o.id_claims = true;
  return o;
}

IdClaim claim(std::uint64_t nonce, std::uint64_t seq) {
  IdClaim c;
  c.nonce = nonce;
  c.seq = seq;
  c.run_id = 0xC1;
  c.expected = 4;
  return c;
}

bool holds(DdsBus& bus, std::uint64_t nonce) {
  const auto all = bus.claim_bus().claims();
  return std::any_of(all.begin(), all.end(), [&](const IdClaim& c) { return c.nonce == nonce; });
}

TEST(IdClaims, AFloodOfNoncesStaysBoundedAndDoesNotHideALaterReplica) {
  DdsBus replica(options("replica"));
  {
    // A stranger floods 200 nonces (more than the 24 kept), then goes quiet.
    DdsBus stranger(options("stranger"));
    std::uint64_t seq = 0;
    ASSERT_TRUE(test::wait_for(
        [&] {
          ++seq;
          for (std::uint64_t n = 1000; n < 1200; ++n)
            stranger.claim_bus().publish_claim(claim(n, seq));
          return holds(replica, 1199);
        },
        30.0));
    EXPECT_EQ(replica.claim_bus().claims().size(), 24u);
  }
  // A replica arriving after it is heard: the flood's nonces are the ones evicted (before: the
  // map, and the keyed reader's instances, stayed full of them and refused every new replica).
  DdsBus late(options("late"));
  std::uint64_t own = 0;
  ASSERT_TRUE(test::wait_for(
      [&] {
        late.claim_bus().publish_claim(claim(7, ++own));
        return holds(replica, 7);
      },
      30.0));
  EXPECT_EQ(replica.claim_bus().claims().size(), 24u);
}

}  // namespace
}  // namespace qswarm
