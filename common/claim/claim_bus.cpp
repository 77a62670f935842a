#include "common/claim/claim_bus.hpp"

#include <algorithm>

namespace qswarm {

bool ClaimInbox::hear(const IdClaim& claim) {
  if (claim.run_id != run_id_) return false;
  std::lock_guard<std::mutex> lock(mu_);
  bool first_eviction = false;
  auto it = by_nonce_.find(claim.nonce);
  if (it == by_nonce_.end()) {
    if (by_nonce_.size() >= capacity_ && !by_nonce_.empty()) {
      by_nonce_.erase(std::min_element(
          by_nonce_.begin(), by_nonce_.end(),
          [](const auto& a, const auto& b) { return a.second.order < b.second.order; }));
      first_eviction = evicted_++ == 0;
    }
    it = by_nonce_.emplace(claim.nonce, Heard{}).first;
  }
  it->second.claim = claim;
  it->second.order = ++heard_;
  return first_eviction;
}

std::vector<IdClaim> ClaimInbox::claims() const {
  std::lock_guard<std::mutex> lock(mu_);
  std::vector<IdClaim> out;
  out.reserve(by_nonce_.size());
  for (const auto& [nonce, h] : by_nonce_) out.push_back(h.claim);
  return out;
}

std::uint64_t ClaimInbox::evicted() const {
  std::lock_guard<std::mutex> lock(mu_);
  return evicted_;
}

void InMemoryClaimNetwork::attach(InMemoryClaimBus* bus) { endpoints_.push_back(bus); }

void InMemoryClaimNetwork::detach(InMemoryClaimBus* bus) {
  endpoints_.erase(std::remove(endpoints_.begin(), endpoints_.end(), bus), endpoints_.end());
  for (auto& [from, c] : queue_)
    if (from == bus) from = nullptr;
}

void InMemoryClaimNetwork::post(const InMemoryClaimBus* from, const IdClaim& claim) {
  queue_.emplace_back(from, claim);
}

void InMemoryClaimNetwork::inject(const IdClaim& claim) { queue_.emplace_back(nullptr, claim); }

void InMemoryClaimNetwork::deliver() {
  std::vector<std::pair<const InMemoryClaimBus*, IdClaim>> round;
  round.swap(queue_);
  // A replica hears its own claims too, as on DDS (the IdClaimer ignores its own).
  for (const auto& [from, c] : round)
    for (InMemoryClaimBus* e : endpoints_) e->receive(c);
}

InMemoryClaimBus::InMemoryClaimBus(InMemoryClaimNetwork& net, std::uint64_t run_id,
                                   std::size_t capacity)
    : net_(net), inbox_(run_id, capacity) {
  net_.attach(this);
}

InMemoryClaimBus::~InMemoryClaimBus() { net_.detach(this); }

}  // namespace qswarm
