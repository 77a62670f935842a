#include "common/dds/dds_bus.hpp"

#include <stdexcept>

namespace qswarm {

DdsBus::DdsBus(const DdsOptions& opts, const Clock& clock)
    : opts_(opts), clock_(clock), participant_(opts.participant) {
  if (opts.id_claims) {
    if (!opts.state.publish) throw std::invalid_argument("dds: id claims need a publishing bus");
    claims_.emplace(participant_, opts.state.run_id, opts.claims_kept);
  }
  if (!opts.claim_first) state_.emplace(participant_, opts.state, clock);
}

void DdsBus::fly_as(AgentId id) {
  if (state_) throw std::logic_error("dds: the state topic is already open");
  StateBusOptions o = opts_.state;
  o.self = id;
  state_.emplace(participant_, o, clock_);
}

DdsStateBus& DdsBus::state() {
  if (!state_) throw std::logic_error("dds: the state topic waits for fly_as");
  return *state_;
}

const DdsStateBus& DdsBus::state() const {
  if (!state_) throw std::logic_error("dds: the state topic waits for fly_as");
  return *state_;
}

ClaimBus& DdsBus::claim_bus() {
  if (!claims_) throw std::logic_error("dds: this bus was made without id claims");
  return *claims_;
}

}  // namespace qswarm
