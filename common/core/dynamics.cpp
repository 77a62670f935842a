#include "common/core/dynamics.hpp"

#include <cmath>

namespace qswarm {
namespace {

Vec3 quadratic_drag(const Vec3& x, const Vec3& c) {
  return Vec3(-x.x() * std::abs(x.x()) * c.x(), -x.y() * std::abs(x.y()) * c.y(),
              -x.z() * std::abs(x.z()) * c.z());
}

QuadState advance(const QuadState& s, const QuadStateDot& d, double h) {
  QuadState out;
  out.p_W = s.p_W + h * d.p_dot_W;
  out.R_WB = s.R_WB + h * d.R_dot;
  out.v_B = s.v_B + h * d.v_dot_B;
  out.omega_B = s.omega_B + h * d.omega_dot_B;
  return out;
}

}  // namespace

bool QuadState::finite() const {
  return p_W.allFinite() && R_WB.allFinite() && v_B.allFinite() && omega_B.allFinite();
}

double total_thrust(const Airframe& af, const RotorSpeeds& w) { return af.K_r * w.squaredNorm(); }

Vec3 rotor_torque(const Airframe& af, const RotorSpeeds& w) {
  const Vec4 u = w.cwiseProduct(w);
  return Vec3(af.K_r * af.arm_m * (u[2] - u[0]), af.K_r * af.arm_m * (u[3] - u[1]),
              af.K_d * (u[0] - u[1] + u[2] - u[3]));
}

ForcesAndTorques forces_and_torques(const Airframe& af, const QuadState& s, const RotorSpeeds& w) {
  ForcesAndTorques ft;
  ft.drag_B = quadratic_drag(s.v_B, af.C_D);
  ft.gravity_B = -af.mass_kg * af.gravity_mps2 * s.R_WB.transpose() * Vec3::UnitZ();
  ft.thrust_B = Vec3(0.0, 0.0, total_thrust(af, w));
  ft.rotor_torque_B = rotor_torque(af, w);
  ft.rot_drag_B = quadratic_drag(s.omega_B, af.C_tau);
  // sum_i Omega x (-1)^(i+1) J_r (0, 0, omega_i) = Omega x (0, 0, J_r (w1 - w2 + w3 - w4)).
  const double spin = af.rotor_inertia_kgm2 * (w[0] - w[1] + w[2] - w[3]);
  ft.gyro_B = s.omega_B.cross(Vec3(0.0, 0.0, spin));
  return ft;
}

QuadStateDot derivatives(const Airframe& af, const QuadState& s, const RotorSpeeds& w) {
  const ForcesAndTorques ft = forces_and_torques(af, s, w);
  const Vec3 J = af.inertia_kgm2;
  QuadStateDot d;
  d.p_dot_W = s.R_WB * s.v_B;
  d.R_dot = s.R_WB * hat(s.omega_B);
  d.v_dot_B = s.v_B.cross(s.omega_B) + (ft.drag_B + ft.gravity_B + ft.thrust_B) / af.mass_kg;
  const Vec3 J_omega = J.cwiseProduct(s.omega_B);
  d.omega_dot_B =
      (J_omega.cross(s.omega_B) + ft.rotor_torque_B + ft.rot_drag_B + ft.gyro_B).cwiseQuotient(J);
  return d;
}

QuadState rk4_step(const Airframe& af, const QuadState& s, const RotorSpeeds& w, double dt) {
  const QuadStateDot k1 = derivatives(af, s, w);
  const QuadStateDot k2 = derivatives(af, advance(s, k1, 0.5 * dt), w);
  const QuadStateDot k3 = derivatives(af, advance(s, k2, 0.5 * dt), w);
  const QuadStateDot k4 = derivatives(af, advance(s, k3, dt), w);
  QuadState out;
  const double h6 = dt / 6.0;
  out.p_W = s.p_W + h6 * (k1.p_dot_W + 2.0 * k2.p_dot_W + 2.0 * k3.p_dot_W + k4.p_dot_W);
  out.R_WB = orthonormalize(s.R_WB + h6 * (k1.R_dot + 2.0 * k2.R_dot + 2.0 * k3.R_dot + k4.R_dot));
  out.v_B = s.v_B + h6 * (k1.v_dot_B + 2.0 * k2.v_dot_B + 2.0 * k3.v_dot_B + k4.v_dot_B);
  out.omega_B = s.omega_B + h6 * (k1.omega_dot_B + 2.0 * k2.omega_dot_B + 2.0 * k3.omega_dot_B +
                                  k4.omega_dot_B);
  return out;
}

}  // namespace qswarm
