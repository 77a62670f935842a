#include "common/dds/dds_bus.hpp"

#include <stdexcept>

namespace qswarm {

DdsBus::DdsBus(const DdsOptions& opts, const Clock& clock)
    : participant_(opts.participant), state_(participant_, opts.state, clock) {
  if (opts.id_claims) {
    if (!opts.state.publish) throw std::invalid_argument("dds: id claims need a publishing bus");
    claims_.emplace(participant_, opts.state.run_id,
                    claim_capacity(static_cast<std::size_t>(opts.state.max_agents)));
  }
}

ClaimBus& DdsBus::claim_bus() {
  if (!claims_) throw std::logic_error("dds: this bus was made without id claims");
  return *claims_;
}

}  // namespace qswarm
