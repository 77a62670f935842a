#include "common/claim/claim_runner.hpp"

#include <random>

namespace qswarm {

std::uint64_t random_nonce() {
  std::random_device rd;
  const std::uint64_t hi = rd();
  const std::uint64_t lo = rd();
  const std::uint64_t n = (hi << 32) ^ lo;
  return n == 0 ? 1 : n;
}

IdClaimRunner::IdClaimRunner(ClaimBus& bus, std::vector<AgentId> roster, std::uint64_t run_id,
                             AgentId fixed, IdClaimer::Config cfg, std::uint64_t nonce,
                             Clock& clock)
    : bus_(bus),
      clock_(clock),
      claimer_(std::move(roster), nonce, run_id, fixed, cfg, clock.now_s()),
      next_progress_s_(clock.now_s() + 10.0) {}

IdClaimer::Step IdClaimRunner::poll(const std::function<void(const std::string&)>& progress) {
  const double now = clock_.now_s();
  const int matched = bus_.claim_writers_matched();
  IdClaimer::Step s = claimer_.step(now, bus_.claims(), matched);
  if (progress && now >= next_progress_s_) {
    progress(claimer_.status(now, matched));
    next_progress_s_ += 10.0;
  }
  if (s.announce) bus_.publish_claim(claimer_.claim());
  return s;
}

std::optional<AgentId> IdClaimRunner::acquire(
    const std::atomic<bool>& stop, std::string& why,
    const std::function<void(const std::string&)>& progress) {
  while (!stop) {
    const IdClaimer::Step s = poll(progress);
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
  const IdClaimer::Step s = poll();
  if (s.refuse) return s.message;
  return std::nullopt;
}

}  // namespace qswarm
