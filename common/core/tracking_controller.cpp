#include "common/core/tracking_controller.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace qswarm {

void TrackingGains::validate() const {
  const auto positive = [](double v, const char* name) {
    if (!std::isfinite(v) || v <= 0.0) {
      throw std::invalid_argument(std::string("gains.") + name + " = " + std::to_string(v) +
                                  ": expected a finite value > 0");
    }
  };
  positive(pos_natural_freq_radps, "pos_natural_freq_radps");
  positive(pos_damping, "pos_damping");
  positive(att_natural_freq_radps, "att_natural_freq_radps");
  positive(att_damping, "att_damping");
  positive(max_pos_error_m, "max_pos_error_m");
  positive(max_climb_accel_mps2, "max_climb_accel_mps2");
  if (!(max_tilt_rad > 0.0 && max_tilt_rad < 1.4)) {
    throw std::invalid_argument("gains.max_tilt_rad = " + std::to_string(max_tilt_rad) +
                                ": expected a value in (0, 1.4)");
  }
}

TrackingOutput track(const Airframe& af, const TrackingGains& k, const QuadState& s,
                     const TrackingReference& ref) {
  const double g = af.gravity_mps2;
  const double wn = k.pos_natural_freq_radps;
  Vec3 e_p = s.p_W - ref.p_W;
  const double e_norm = e_p.norm();
  if (e_norm > k.max_pos_error_m) e_p *= k.max_pos_error_m / e_norm;
  const Vec3 e_v = s.velocity_W() - ref.v_W;
  Vec3 a_cmd = -wn * wn * e_p - 2.0 * k.pos_damping * wn * e_v + ref.a_W;

  // Limit the command to what the airframe can fly level-ish: vertical first, then tilt.
  a_cmd.z() = std::clamp(a_cmd.z(), -0.8 * g, k.max_climb_accel_mps2);
  const double a_h_max = (g + a_cmd.z()) * std::tan(k.max_tilt_rad);
  const double a_h = std::hypot(a_cmd.x(), a_cmd.y());
  if (a_h > a_h_max) {
    a_cmd.x() *= a_h_max / a_h;
    a_cmd.y() *= a_h_max / a_h;
  }
  const Vec3 F_W = af.mass_kg * (a_cmd + g * Vec3::UnitZ());

  TrackingOutput out;
  const Vec3 b3_d = F_W.normalized();
  const Vec3 b1_c(std::cos(ref.yaw_rad), std::sin(ref.yaw_rad), 0.0);
  const Vec3 b2_d = b3_d.cross(b1_c).normalized();
  const Vec3 b1_d = b2_d.cross(b3_d);
  out.R_desired.col(0) = b1_d;
  out.R_desired.col(1) = b2_d;
  out.R_desired.col(2) = b3_d;

  const Vec3 e_R =
      0.5 * vee(out.R_desired.transpose() * s.R_WB - s.R_WB.transpose() * out.R_desired);
  const Vec3 J = af.inertia_kgm2;
  const double wa = k.att_natural_freq_radps;
  const Vec3 k_R = wa * wa * J;
  const Vec3 k_W = 2.0 * k.att_damping * wa * J;
  const Vec3 J_omega = J.cwiseProduct(s.omega_B);
  // Also cancel the rotational drag tau_1, which the allocation cannot see.
  const Vec3 rot_drag(-s.omega_B.x() * std::abs(s.omega_B.x()) * af.C_tau.x(),
                      -s.omega_B.y() * std::abs(s.omega_B.y()) * af.C_tau.y(),
                      -s.omega_B.z() * std::abs(s.omega_B.z()) * af.C_tau.z());
  out.wrench.torque_B_Nm =
      -k_R.cwiseProduct(e_R) - k_W.cwiseProduct(s.omega_B) + s.omega_B.cross(J_omega) - rot_drag;
  out.wrench.thrust_N = std::max(0.0, F_W.dot(s.R_WB.col(2)));
  out.allocation = allocate(af, out.wrench);
  return out;
}

}  // namespace qswarm
