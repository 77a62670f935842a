#include "common/core/allocation.hpp"

#include <algorithm>
#include <cmath>

namespace qswarm {
namespace {

// u = omega^2 for a wrench, exact inverse of wrench_from_rotors.
Vec4 inverse(const Airframe& af, double thrust, const Vec3& tau) {
  const double sum = thrust / af.K_r;                // u1 + u2 + u3 + u4
  const double alt = tau.z() / af.K_d;               // u1 - u2 + u3 - u4
  const double d13 = tau.x() / (af.K_r * af.arm_m);  // u3 - u1
  const double d24 = tau.y() / (af.K_r * af.arm_m);  // u4 - u2
  const double s13 = 0.5 * (sum + alt);
  const double s24 = 0.5 * (sum - alt);
  return Vec4(0.5 * (s13 - d13), 0.5 * (s24 - d24), 0.5 * (s13 + d13), 0.5 * (s24 + d24));
}

// Largest s in [0, 1] with lo <= base + s * delta <= hi componentwise (assuming base is inside).
double max_fraction(const Vec4& base, const Vec4& delta, double lo, double hi) {
  double s = 1.0;
  for (int i = 0; i < 4; ++i) {
    if (delta[i] > 0.0) s = std::min(s, (hi - base[i]) / delta[i]);
    if (delta[i] < 0.0) s = std::min(s, (lo - base[i]) / delta[i]);
  }
  return std::clamp(s, 0.0, 1.0);
}

bool inside(const Vec4& u, double lo, double hi) {
  return (u.array() >= lo - 1e-9).all() && (u.array() <= hi + 1e-9).all();
}

}  // namespace

Wrench wrench_from_rotors(const Airframe& af, const RotorSpeeds& w) {
  return Wrench{total_thrust(af, w), rotor_torque(af, w)};
}

Allocation allocate(const Airframe& af, const Wrench& desired) {
  const double lo = af.rotor_min_radps * af.rotor_min_radps;
  const double hi = af.rotor_max_radps * af.rotor_max_radps;
  Allocation out;
  Vec4 u = inverse(af, desired.thrust_N, desired.torque_B_Nm);
  if (!inside(u, lo, hi)) {
    out.saturated = true;
    const double thrust = std::clamp(desired.thrust_N, 4.0 * af.K_r * lo,
                                     4.0 * af.K_r * hi);  // thrust alone always fits
    const Vec4 u_thrust = inverse(af, thrust, Vec3::Zero());
    const Vec3 tau_rp(desired.torque_B_Nm.x(), desired.torque_B_Nm.y(), 0.0);
    const Vec4 du_rp = inverse(af, 0.0, tau_rp);
    const double s_rp = max_fraction(u_thrust, du_rp, lo, hi);
    const Vec4 u_rp = u_thrust + s_rp * du_rp;
    const Vec4 du_yaw = inverse(af, 0.0, Vec3(0.0, 0.0, desired.torque_B_Nm.z()));
    const double s_yaw = s_rp < 1.0 ? 0.0 : max_fraction(u_rp, du_yaw, lo, hi);
    u = u_rp + s_yaw * du_yaw;
  }
  for (int i = 0; i < 4; ++i) out.omega_radps[i] = std::sqrt(std::clamp(u[i], lo, hi));
  return out;
}

}  // namespace qswarm
