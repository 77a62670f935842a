#pragma once

#include <cstddef>
#include <cstdint>

namespace qswarm {

using AgentId = std::uint32_t;

// The largest swarm a run may have (the scenario refuses more): every list in a state message
// (links, flows, copies) has at most kMaxSwarmAgents - 1 entries, and the wire carries them all.
inline constexpr std::size_t kMaxSwarmAgents = 512;

// What an agent's samples say of its pose (wire and record field `mode`): a position only, or also
// an attitude and four rotor speeds (a plant with PlantSpec::oriented: the paper's quadcopter).
enum class PoseKind : std::uint8_t { kPosition = 0, kOriented = 1 };

}  // namespace qswarm
