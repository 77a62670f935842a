#pragma once

#include <atomic>
#include <functional>
#include <optional>
#include <string>

#include "common/dds/dds_bus.hpp"
#include "common/runtime/clock.hpp"
#include "common/runtime/id_claimer.hpp"
#include "common/runtime/run_config.hpp"

namespace qswarm {

// swarm-agent's side of the id claim (--id auto, or --claim with a given id): drives the
// IdClaimer over the DDS claim topic, before the flight and during it.
class IdClaimRunner {
 public:
  // `fixed`: the id given by hand, 0 for auto; `timeout_s` < 0: the default for the swarm's size.
  IdClaimRunner(DdsBus& bus, const RunConfig& rc, AgentId fixed, double timeout_s, Clock& clock);

  // Waits until an id is taken (returned), the claim is refused (`why` says why) or `stop` is set;
  // says where it stands through `progress` every 10 s.
  std::optional<AgentId> acquire(const std::atomic<bool>& stop, std::string& why,
                                 const std::function<void(const std::string&)>& progress);
  // While flying: keeps announcing the claim. Returns why this replica must stop (another one holds
  // its id and keeps it), or nothing.
  std::optional<std::string> keep();

  std::uint64_t nonce() const { return claimer_.claim().nonce; }

 private:
  DdsBus& bus_;
  Clock& clock_;
  IdClaimer claimer_;
};

// A random 64-bit replica nonce (from the OS's entropy).
std::uint64_t random_nonce();

}  // namespace qswarm
