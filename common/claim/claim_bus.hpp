#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <mutex>
#include <vector>

#include "common/claim/id_claim.hpp"

namespace qswarm {

// What the id claim needs of a transport: announce this replica's claim, hear the others'. DDS
// implements it for the product (the topic qswarm/id_claim), InMemoryClaimBus for tests.
class ClaimBus {
 public:
  virtual ~ClaimBus() = default;
  virtual void publish_claim(const IdClaim& claim) = 0;
  // The latest claim of every replica heard (a bounded number of them: see ClaimInbox).
  virtual std::vector<IdClaim> claims() const = 0;
  // Claim writers matched to this replica's reader, its own included; -1 when the transport has
  // no matching to report (the in-memory bus).
  virtual int claim_writers_matched() const { return -1; }
};

// The latest claim of each replica heard, at most `capacity` of them: a new nonce arriving when it
// is full evicts the one heard longest ago. Nonces a stranger flooded once, or replicas that
// restarted, are gone once enough newer ones are heard, and a live replica evicted comes back with
// its next claim. Claims of another run are not kept. Thread-safe (a transport thread hears).
class ClaimInbox {
 public:
  ClaimInbox(std::uint64_t run_id, std::size_t capacity) : run_id_(run_id), capacity_(capacity) {}
  // Returns true when this claim evicted another for the first time (worth one log line).
  bool hear(const IdClaim& claim);
  std::vector<IdClaim> claims() const;
  std::uint64_t evicted() const;

 private:
  struct Heard {
    IdClaim claim;
    std::uint64_t order = 0;  // `heard_` when this nonce was last heard: the eviction order
  };
  std::uint64_t run_id_;
  std::size_t capacity_;
  mutable std::mutex mu_;
  std::map<std::uint64_t, Heard> by_nonce_;
  std::uint64_t heard_ = 0;
  std::uint64_t evicted_ = 0;
};

class InMemoryClaimBus;

// Replicas in one process: what one posts reaches every other endpoint at deliver(), so a test
// steps many IdClaimRunners on one ManualClock. Deterministic; single-threaded.
class InMemoryClaimNetwork {
 public:
  void attach(InMemoryClaimBus* bus);
  void detach(InMemoryClaimBus* bus);
  void post(const InMemoryClaimBus* from, const IdClaim& claim);
  void deliver();
  // A stranger's claim (a test acting as one on the network).
  void inject(const IdClaim& claim);

 private:
  std::vector<InMemoryClaimBus*> endpoints_;
  std::vector<std::pair<const InMemoryClaimBus*, IdClaim>> queue_;
};

class InMemoryClaimBus final : public ClaimBus {
 public:
  InMemoryClaimBus(InMemoryClaimNetwork& net, std::uint64_t run_id, std::size_t capacity);
  ~InMemoryClaimBus() override;
  InMemoryClaimBus(const InMemoryClaimBus&) = delete;
  InMemoryClaimBus& operator=(const InMemoryClaimBus&) = delete;

  void publish_claim(const IdClaim& claim) override { net_.post(this, claim); }
  std::vector<IdClaim> claims() const override { return inbox_.claims(); }
  void receive(const IdClaim& claim) { inbox_.hear(claim); }

 private:
  InMemoryClaimNetwork& net_;
  ClaimInbox inbox_;
};

}  // namespace qswarm
