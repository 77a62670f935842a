#pragma once

#include <cstddef>

#include "common/claim/id_claim.hpp"
#include "common/transport/state_message.hpp"
#include "swarm_state.h"

namespace qswarm {

// The bound of every list in the wire type (idl/swarm_state.idl): an agent has at most
// kMaxSwarmAgents - 1 peers, so its links, flows and copies always fit.
inline constexpr std::size_t kMaxWireEntries = 511;
static_assert(kMaxWireEntries + 1 >= kMaxSwarmAgents, "the wire must carry the largest swarm");

// StateMessage <-> the generated DDS type. to_idl throws std::length_error if a list exceeds the
// wire's bound (never cuts it).
void to_idl(const StateMessage& m, qswarm_msgs::AgentState& s);
StateMessage from_idl(const qswarm_msgs::AgentState& s);
// The same into `m`, every field overwritten and its lists' storage reused (the receive path).
void from_idl(const qswarm_msgs::AgentState& s, StateMessage& m);

// IdClaim <-> its DDS type.
void to_idl(const IdClaim& c, qswarm_msgs::IdClaim& s);
IdClaim from_idl(const qswarm_msgs::IdClaim& s);

}  // namespace qswarm
