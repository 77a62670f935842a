#pragma once

#include <cstddef>
#include <cstdint>

namespace qswarm {

using AgentId = std::uint32_t;

// The largest swarm a run may have (the scenario refuses more): every list in a state message
// (links, flows, copies) has at most kMaxSwarmAgents - 1 entries, and the wire carries them all.
inline constexpr std::size_t kMaxSwarmAgents = 512;

// What an agent flies: the paper's point (section 2: its position is its consensus state) or a
// quadcopter tracking its consensus state (sections 3-4).
enum class AgentMode : std::uint8_t { kParticle = 0, kQuadcopter = 1 };

}  // namespace qswarm
