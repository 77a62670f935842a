#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "common/claim/claim_bus.hpp"
#include "common/dds/participant.hpp"

namespace qswarm {

// The id claims over DDS: the topic "qswarm/id_claim" on a participant (swarm-agent --id auto, the
// compose swarm). The topic has no key, so DDS keeps no state per nonce: a best-effort queue of the
// latest claims, taken as they arrive into a bounded ClaimInbox.
class DdsClaimBus final : public ClaimBus {
 public:
  // `capacity`: how many replicas' claims are kept (claim_capacity(N)). The participant must
  // outlive the bus.
  DdsClaimBus(DdsParticipant& participant, std::uint64_t run_id, std::size_t capacity);
  ~DdsClaimBus() override;
  DdsClaimBus(const DdsClaimBus&) = delete;
  DdsClaimBus& operator=(const DdsClaimBus&) = delete;

  void publish_claim(const IdClaim& claim) override;
  std::vector<IdClaim> claims() const override;
  // Claim writers matched to this participant's claim reader (its own included).
  int claim_writers_matched() const override;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace qswarm
