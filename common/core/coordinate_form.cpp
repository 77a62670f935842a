#include "common/core/coordinate_form.hpp"

#include <cmath>

namespace qswarm {

CoordinateState coordinate_derivatives(const Airframe& af, const CoordinateState& x,
                                       const RotorSpeeds& w) {
  const double phi = x[3], theta = x[4], psi = x[5];
  const double v1 = x[6], v2 = x[7], v3 = x[8];
  const double O1 = x[9], O2 = x[10], O3 = x[11];
  const double Cf = std::cos(phi), Sf = std::sin(phi);
  const double Ct = std::cos(theta), St = std::sin(theta), Tt = std::tan(theta);
  const double Cp = std::cos(psi), Sp = std::sin(psi);
  const double m = af.mass_kg, g = af.gravity_mps2;
  const double J1 = af.inertia_kgm2[0], J2 = af.inertia_kgm2[1], J3 = af.inertia_kgm2[2];
  const double Jr = af.rotor_inertia_kgm2;
  double sum_t = 0.0;
  for (int i = 0; i < 4; ++i) sum_t += af.K_r * w[i] * w[i];
  const double alt_w = w[0] - w[1] + w[2] - w[3];  // sum (-1)^(i+1) w_i
  const double alt_w2 = w[0] * w[0] - w[1] * w[1] + w[2] * w[2] - w[3] * w[3];  // ... w_i^2

  CoordinateState d;
  d[0] = v1 * Cp * Ct + v2 * (Cp * St * Sf - Sp * Cf) + v3 * (Cp * St * Cf + Sp * Sf);
  d[1] = v1 * Sp * Ct + v2 * (Sp * St * Sf + Cp * Cf) + v3 * (Sp * St * Cf - Cp * Sf);
  d[2] = -v1 * St + v2 * Ct * Sf + v3 * Ct * Cf;
  d[3] = O1 + O2 * Sf * Tt + O3 * Cf * Tt;
  d[4] = O2 * Cf - O3 * Sf;
  d[5] = O2 * Sf / Ct + O3 * Cf / Ct;
  d[6] = v2 * O3 - v3 * O2 - v1 * std::abs(v1) * af.C_D[0] / m + g * St;
  d[7] = v3 * O1 - v1 * O3 - v2 * std::abs(v2) * af.C_D[1] / m - g * Ct * Sf;
  d[8] = v1 * O2 - v2 * O1 + (sum_t - v3 * std::abs(v3) * af.C_D[2]) / m - g * Ct * Cf;
  d[9] = ((J2 - J3) * O2 * O3 + Jr * alt_w * O2 + af.K_r * af.arm_m * (w[2] * w[2] - w[0] * w[0]) -
          O1 * std::abs(O1) * af.C_tau[0]) /
         J1;
  d[10] = ((J3 - J1) * O1 * O3 - Jr * alt_w * O1 + af.K_r * af.arm_m * (w[3] * w[3] - w[1] * w[1]) -
           O2 * std::abs(O2) * af.C_tau[1]) /
          J2;
  d[11] = ((J1 - J2) * O1 * O2 + af.K_d * alt_w2 - O3 * std::abs(O3) * af.C_tau[2]) / J3;
  return d;
}

CoordinateState coordinate_rk4_step(const Airframe& af, const CoordinateState& x,
                                    const RotorSpeeds& w, double dt) {
  const CoordinateState k1 = coordinate_derivatives(af, x, w);
  const CoordinateState k2 = coordinate_derivatives(af, x + 0.5 * dt * k1, w);
  const CoordinateState k3 = coordinate_derivatives(af, x + 0.5 * dt * k2, w);
  const CoordinateState k4 = coordinate_derivatives(af, x + dt * k3, w);
  return x + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
}

CoordinateState to_coordinates(const QuadState& s) {
  const TaitBryan a = tait_bryan_from_rotation(s.R_WB);
  CoordinateState x;
  x << s.p_W, a.roll_rad, a.pitch_rad, a.yaw_rad, s.v_B, s.omega_B;
  return x;
}

QuadState from_coordinates(const CoordinateState& x) {
  QuadState s;
  s.p_W = x.segment<3>(0);
  s.R_WB = rotation_from_tait_bryan({x[3], x[4], x[5]});
  s.v_B = x.segment<3>(6);
  s.omega_B = x.segment<3>(9);
  return s;
}

}  // namespace qswarm
