#pragma once

#include "common/core/airframe.hpp"
#include "common/core/math.hpp"

namespace qswarm {

// Rotor angular speeds omega_1..omega_4 [rad/s], numbered as in the paper: rotors 1 and 3 on the
// body x axis (-x and +x side by tau_f's sign), 2 and 4 on the body y axis; odd rotors spin one
// way, even the other (the (-1)^(i+1) factors).
using RotorSpeeds = Vec4;

// State on SE(3) x R^6, the paper's (b, R, v, Omega). The integrator works on this, never on
// angles.
struct QuadState {
  Vec3 p_W = Vec3::Zero();       // b: centre of mass, inertial frame [m]
  Mat3 R_WB = Mat3::Identity();  // R: body-to-inertial rotation
  Vec3 v_B = Vec3::Zero();       // v: translational velocity, body frame [m/s]
  Vec3 omega_B = Vec3::Zero();   // Omega: angular velocity, body frame [rad/s]

  Vec3 velocity_W() const { return R_WB * v_B; }
  bool finite() const;
};

struct QuadStateDot {
  Vec3 p_dot_W;
  Mat3 R_dot;
  Vec3 v_dot_B;
  Vec3 omega_dot_B;
};

// The individual terms of the paper's equations (3.x "External forces and torques"), body frame.
struct ForcesAndTorques {
  Vec3 drag_B;          // f_1 = -diag(v|v|) C_D                 [N]
  Vec3 gravity_B;       // f_2 = -m g R^T e3                     [N]
  Vec3 thrust_B;        // f_3 = sum_i K_r omega_i^2 e3          [N]
  Vec3 rotor_torque_B;  // tau_f                                 [N m]
  Vec3 rot_drag_B;      // tau_1 = -diag(Omega|Omega|) C_tau     [N m]
  Vec3 gyro_B;          // tau_2 = sum_i Omega x (-1)^(i+1) J_r (0,0,omega_i) [N m]
};

ForcesAndTorques forces_and_torques(const Airframe& af, const QuadState& s, const RotorSpeeds& w);

// tau_f alone: (K_r d (w3^2 - w1^2), K_r d (w4^2 - w2^2), K_d sum (-1)^(i+1) w_i^2).
Vec3 rotor_torque(const Airframe& af, const RotorSpeeds& w);
double total_thrust(const Airframe& af, const RotorSpeeds& w);

// The geometric equations of motion (paper eqs. b' = Rv, R' = R hat(Omega),
// m v' = m v x Omega + f1 + f2 + f3, J Omega' = J Omega x Omega + tau_f + tau_1 + tau_2).
QuadStateDot derivatives(const Airframe& af, const QuadState& s, const RotorSpeeds& w);

// One classical fixed-step RK4 step with rotor speeds held over the step (zero-order hold); the
// rotation is projected back onto SO(3) afterwards.
QuadState rk4_step(const Airframe& af, const QuadState& s, const RotorSpeeds& w, double dt_s);

}  // namespace qswarm
