#pragma once

#include <optional>
#include <set>
#include <vector>

#include "common/claim/claim_bus.hpp"
#include "common/clock/clock.hpp"
#include "common/dds/claim_bus.hpp"
#include "common/dds/participant.hpp"
#include "common/dds/state_bus.hpp"

namespace qswarm {

struct DdsOptions {
  ParticipantOptions participant;
  StateBusOptions state;
  bool id_claims = false;  // also the id-claim topic (swarm-agent --id auto, the compose swarm)
};

// What one process of the swarm speaks over DDS: its one participant, the state topic as the
// NeighborBus it flies on and, for a replica that claims its id, the claim topic as its ClaimBus.
class DdsBus final : public NeighborBus {
 public:
  explicit DdsBus(const DdsOptions& opts, const Clock& clock = system_clock());

  void publish(const StateMessage& msg) override { state_.publish(msg); }
  void record(const StateMessage& msg) override { state_.record(msg); }
  bool recorder_confirmed() const override { return state_.recorder_confirmed(); }
  int record_readers_matched() const { return state_.record_readers_matched(); }
  void set_interest(const Interest& interest) override { state_.set_interest(interest); }
  void for_each_latest(AgentId self,
                       const std::function<void(const StateMessage&)>& visit) override {
    state_.for_each_latest(self, visit);
  }
  void set_listener(Listener listener) override { state_.set_listener(std::move(listener)); }
  BusCounters counters() const override { return state_.counters(); }
  int matched_readers() const override { return state_.matched_readers(); }
  std::set<std::uint64_t> foreign_runs() const override { return state_.foreign_runs(); }
  std::set<AgentId> strangers() const override { return state_.strangers(); }
  std::map<AgentId, std::uint8_t> suspects() const override { return state_.suspects(); }

  // The claim topic (DdsOptions::id_claims; std::logic_error without it).
  ClaimBus& claim_bus();
  DdsParticipant& participant() { return participant_; }
  DdsStateBus& state() { return state_; }

 private:
  DdsParticipant participant_;
  DdsStateBus state_;
  std::optional<DdsClaimBus> claims_;  // deleted before the state bus and the participant
};

}  // namespace qswarm
