#pragma once

#include "common/core/airframe.hpp"
#include "common/core/dynamics.hpp"

namespace qswarm {

// Collective thrust along body z and the three rotor torques tau_f.
struct Wrench {
  double thrust_N = 0.0;
  Vec3 torque_B_Nm = Vec3::Zero();
};

// The paper's allocation (Proposition "affine control system", u_i = omega_i^2):
//   thrust = K_r sum u_i, tau_f = (K_r d (u3 - u1), K_r d (u4 - u2), K_d (u1 - u2 + u3 - u4)).
Wrench wrench_from_rotors(const Airframe& af, const RotorSpeeds& w);

struct Allocation {
  RotorSpeeds omega_radps = RotorSpeeds::Zero();
  bool saturated = false;  // the requested wrench was changed to respect rotor limits
};

// Inverse of the allocation, then rotor limits. When the exact inverse needs a rotor speed outside
// [rotor_min, rotor_max], authority is given up in this order: yaw torque first, then roll/pitch
// torque (scaled together, keeping the tilt direction), then thrust is clamped. Always returns
// speeds within the airframe's limits.
Allocation allocate(const Airframe& af, const Wrench& desired);

}  // namespace qswarm
