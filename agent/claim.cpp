#include "agent/claim.hpp"

#include <algorithm>
#include <random>
#include <vector>

namespace qswarm {

namespace {
// Every replica announces to every other: N^2 claims per period. Ten a second suits a few; for
// more the period grows (2 a second at 32 replicas) and so do the windows that depend on it.
IdClaimer::Config claim_config(double timeout_s, std::size_t n) {
  IdClaimer::Config c;
  c.timeout_s = timeout_s;
  c.period_s = 0.1 * std::max(1.0, static_cast<double>(n) / 6.0);
  c.expire_s = std::max(c.expire_s, 6.0 * c.period_s);
  c.settle_s = std::max(c.settle_s, 3.0 * c.period_s);
  c.confirm_s = std::max(c.confirm_s, 3.0 * c.period_s);
  return c;
}
std::vector<AgentId> roster_of(const RunConfig& rc) {
  const std::set<AgentId> ids = rc.ids();
  return {ids.begin(), ids.end()};
}
}  // namespace

std::uint64_t random_nonce() {
  std::random_device rd;
  const std::uint64_t hi = rd();
  const std::uint64_t lo = rd();
  const std::uint64_t n = (hi << 32) ^ lo;
  return n == 0 ? 1 : n;
}

IdClaimRunner::IdClaimRunner(DdsBus& bus, const RunConfig& rc, AgentId fixed, double timeout_s,
                             Clock& clock)
    : bus_(bus),
      clock_(clock),
      claimer_(roster_of(rc), random_nonce(), rc.run_id, fixed,
               claim_config(timeout_s, rc.agents.size()), clock.now_s()) {}

std::optional<AgentId> IdClaimRunner::acquire(const std::atomic<bool>& stop, std::string& why) {
  while (!stop) {
    const IdClaimer::Step s =
        claimer_.step(clock_.now_s(), bus_.claims(), bus_.claim_writers_matched());
    if (s.announce) bus_.publish_claim(claimer_.claim());
    if (s.refuse) {
      why = s.message;
      return std::nullopt;
    }
    if (s.taken != 0) return s.taken;
    clock_.sleep_until(clock_.now_s() + 0.02);
  }
  why = "stopped before an id was taken";
  return std::nullopt;
}

std::optional<std::string> IdClaimRunner::keep() {
  const IdClaimer::Step s =
      claimer_.step(clock_.now_s(), bus_.claims(), bus_.claim_writers_matched());
  if (s.announce) bus_.publish_claim(claimer_.claim());
  if (s.refuse) return s.message;
  return std::nullopt;
}

}  // namespace qswarm
