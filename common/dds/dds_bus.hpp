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
  // The state topic waits for fly_as (a replica claims its id first: its reader then leaves out
  // its own samples from the start).
  bool claim_first = false;
  std::size_t claims_kept = 16;  // how many replicas' claims it keeps (RunPlan::claim_capacity)
};

// What one process of the swarm speaks over DDS: its one participant, the state topic as the
// NeighborBus it flies on and, for a replica that claims its id, the claim topic as its ClaimBus.
class DdsBus final : public NeighborBus {
 public:
  explicit DdsBus(const DdsOptions& opts, const Clock& clock = system_clock());

  // The state topic, flying as agent `id` (DdsOptions::claim_first: once its id is claimed).
  void fly_as(AgentId id);

  void publish(const StateMessage& msg) override { state().publish(msg); }
  void record(const StateMessage& msg) override { state().record(msg); }
  bool recorder_confirmed() const override { return state().recorder_confirmed(); }
  int record_readers_matched() const { return state().record_readers_matched(); }
  void set_interest(const Interest& interest) override { state().set_interest(interest); }
  void for_each_latest(AgentId self,
                       const std::function<void(const StateMessage&)>& visit) override {
    state().for_each_latest(self, visit);
  }
  void set_listener(Listener listener) override { state().set_listener(std::move(listener)); }
  BusCounters counters() const override { return state().counters(); }
  int matched_readers() const override { return state().matched_readers(); }
  std::set<std::uint64_t> foreign_runs() const override { return state().foreign_runs(); }
  std::set<AgentId> strangers() const override { return state().strangers(); }
  std::map<AgentId, std::uint8_t> suspects() const override { return state().suspects(); }

  // The claim topic (DdsOptions::id_claims; std::logic_error without it).
  ClaimBus& claim_bus();
  DdsParticipant& participant() { return participant_; }
  // The state topic (std::logic_error before fly_as under claim_first).
  DdsStateBus& state();
  const DdsStateBus& state() const;

 private:
  DdsOptions opts_;
  const Clock& clock_;
  DdsParticipant participant_;
  std::optional<DdsStateBus> state_;
  std::optional<DdsClaimBus> claims_;  // deleted before the state bus and the participant
};

}  // namespace qswarm
