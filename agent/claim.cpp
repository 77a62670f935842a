#include "agent/claim.hpp"

#include <random>
#include <vector>

namespace qswarm {

namespace {
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
               IdClaimer::Config::for_swarm(rc.agents.size(), timeout_s), clock.now_s()) {}

std::optional<AgentId> IdClaimRunner::acquire(
    const std::atomic<bool>& stop, std::string& why,
    const std::function<void(const std::string&)>& progress) {
  double next_progress_s = clock_.now_s() + 10.0;
  while (!stop) {
    const int matched = bus_.claim_writers_matched();
    const IdClaimer::Step s = claimer_.step(clock_.now_s(), bus_.claims(), matched);
    if (clock_.now_s() >= next_progress_s) {
      progress(claimer_.status(clock_.now_s(), matched));
      next_progress_s += 10.0;
    }
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
