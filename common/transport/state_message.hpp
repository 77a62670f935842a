#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "common/core/dynamics.hpp"
#include "common/core/update_law.hpp"

namespace qswarm {

enum class AgentMode : std::uint8_t { kParticle = 0, kQuadcopter = 1 };

// One agent's published state: the consensus part its neighbours' laws read, plus the physical
// part the supervisor records. The DDS type in idl/ mirrors this.
struct StateMessage {
  NeighborView view;  // id, consensus state, total weight, owned flows
  std::uint64_t seq = 0;
  double stamp_s = 0.0;  // sender's run time
  AgentMode mode = AgentMode::kParticle;
  Vec3 p_W = Vec3::Zero();
  Vec3 v_W = Vec3::Zero();
  Eigen::Quaterniond q_WB = Eigen::Quaterniond::Identity();
  RotorSpeeds rotors_radps = RotorSpeeds::Zero();
  std::vector<std::pair<AgentId, double>> links;  // edges the sender holds, with weights
};

}  // namespace qswarm
