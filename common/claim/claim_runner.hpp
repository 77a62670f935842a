#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "common/claim/claim_bus.hpp"
#include "common/claim/id_claimer.hpp"
#include "common/clock/clock.hpp"

namespace qswarm {

// A replica's side of the id claim (swarm-agent --id auto, or --claim with a given id): drives the
// IdClaimer over a claim bus on a clock, before the flight and during it. swarm-agent runs it over
// DDS on a SteadyClock; tests run many over an InMemoryClaimNetwork on one ManualClock.
class IdClaimRunner {
 public:
  // `roster`: the run's agent ids; `fixed`: the id given by hand, 0 for auto.
  IdClaimRunner(ClaimBus& bus, std::vector<AgentId> roster, std::uint64_t run_id, AgentId fixed,
                IdClaimer::Config cfg, std::uint64_t nonce, Clock& clock);

  // One step on the clock's time: announces when due and says whether an id is taken (or the
  // claim refused). `progress` (if set) hears where the claim stands every 10 s while it waits.
  IdClaimer::Step poll(const std::function<void(const std::string&)>& progress = {});
  // Polls every 20 ms until an id is taken (returned), the claim is refused (`why` says why) or
  // `stop` is set.
  std::optional<AgentId> acquire(const std::atomic<bool>& stop, std::string& why,
                                 const std::function<void(const std::string&)>& progress);
  // While flying: keeps announcing the claim. Returns why this replica must stop (another one holds
  // its id and keeps it), or nothing.
  std::optional<std::string> keep();

  std::uint64_t nonce() const { return claimer_.claim().nonce; }
  const IdClaimer& claimer() const { return claimer_; }

 private:
  ClaimBus& bus_;
  Clock& clock_;
  IdClaimer claimer_;
  double next_progress_s_;
};

// A random 64-bit replica nonce (from the OS's entropy).
std::uint64_t random_nonce();

}  // namespace qswarm
