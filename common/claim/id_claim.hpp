#pragma once

#include <cstdint>

#include "common/core/update_law.hpp"

namespace qswarm {

// One replica's claim to an agent id (swarm-agent --id auto, the compose swarm). The DDS type
// IdClaim in idl/ mirrors it. See common/claim/id_claimer.hpp for the protocol.
struct IdClaim {
  std::uint64_t nonce = 0;     // random, drawn once per replica: the replica's identity
  std::uint64_t seq = 0;       // counts the sender's claims: a changing value means it is alive
  std::uint64_t run_id = 0;    // the run the replica belongs to
  std::uint32_t expected = 0;  // the swarm's size this replica was told
  AgentId id = 0;              // the id taken (or given by hand); 0 while an auto replica ranks
  std::uint8_t stage = 0;      // ClaimStage
  double flying_s = 0.0;       // how long the sender has flown its id (kFlying)
};

// A replica ranks (no id yet), then confirms an id for a while (announcing it, not flying it: a
// conflict found now costs nothing), then flies it. Of two flying one id, the earlier flight
// keeps it.
enum ClaimStage : std::uint8_t { kRanking = 0, kConfirming = 1, kFlying = 2 };

}  // namespace qswarm
