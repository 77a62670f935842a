#pragma once

#include <vector>

#include "common/core/airframe.hpp"
#include "common/core/dynamics.hpp"

namespace qswarm {

// The paper's open-loop motion primitives (section 4.1).

// Hover: omega_i = sqrt(m g / (4 K_r)).
RotorSpeeds hover_rotors(const Airframe& af);

// Yaw Lemma: omega1 = omega3 = sqrt(m g / (2 K_r) - omega2^2), omega4 = omega2 (omega2 free).
RotorSpeeds yaw_lemma_rotors(const Airframe& af, double omega2_radps);
// The free parameter omega2 that makes the yaw Lemma's rotors produce yaw torque tau_z:
// tau_z = 2 K_d (omega1^2 - omega2^2) = 2 K_d (m g / (2 K_r) - 2 omega2^2).
double yaw_lemma_omega2_for_torque(const Airframe& af, double tau_z_Nm);

// x-axis Lemma: omega2 = (sqrt((6a - 8 K_r omega4^2) / K_r) - omega4) / 3, omega1 = omega3 =
// (omega2 + omega4) / 2, where a = sum of thrusts (omega4 free).
RotorSpeeds x_axis_lemma_rotors(const Airframe& af, double a_thrust_N, double omega4_radps);
// The Lemma's a (the thrust that keeps b3 constant) for the current state; v1_dot is taken from
// the equations of motion at that state.
double x_axis_lemma_thrust(const Airframe& af, const QuadState& s);
// The free parameter omega4 that, with the x-axis Lemma's relations and thrust a, gives pitch
// torque tau_y = K_r d (omega4^2 - omega2^2). Clamped to the Lemma's domain (omega2 >= 0).
double x_axis_lemma_omega4_for_torque(const Airframe& af, double a_thrust_N, double tau_y_Nm);
// The yaw torque the x-axis Lemma leaves: K_d (w1^2 - w2^2 + w3^2 - w4^2), which with
// w1 = w3 = (w2 + w4)/2 equals -K_d (w2 - w4)^2 / 2: never positive, zero only when w2 == w4, i.e.
// only when the body is not being pitched. So the Lemma's "no yaw" holds only to first order.
double x_axis_lemma_yaw_torque(const Airframe& af, double omega2_radps, double omega4_radps);

// A sequence of the paper's primitives, flown open loop: each segment fixes the paper's rotor
// relations and the Lemma's free parameter is chosen each step from a smooth profile (angle or
// distance over the segment's duration) with light feedback on that one angle.
class OpenLoopManeuver {
 public:
  enum class Kind { kHover, kClimb, kYaw, kBodyX };
  struct Segment {
    Kind kind = Kind::kHover;
    double duration_s = 0.0;
    double amount = 0.0;  // climb: metres up; yaw: radians; body x: metres along body x
  };

  explicit OpenLoopManeuver(Airframe af, std::vector<Segment> segments);

  // The paper's single-agent figure: rise for 12 s, yaw +pi/2 over 4 s, fly along body x for 4 s.
  static OpenLoopManeuver paper_single_agent(const Airframe& af, double climb_m = 10.0,
                                             double forward_m = 4.0);
  // One drone of the paper's 3-drone rendezvous: yaw to face the target, then fly to it along body
  // x.
  static OpenLoopManeuver yaw_then_fly(const Airframe& af, const QuadState& start,
                                       const Vec3& target, double yaw_duration_s = 4.0,
                                       double max_pitch_rad = 0.15);

  // Rotor speeds at time t for the current state (the state enters only where the Lemma's formulas
  // use it, and through the feedback on the profiled angle).
  RotorSpeeds command(double t_s, const QuadState& s);
  double duration_s() const;
  const std::vector<Segment>& segments() const { return segments_; }

 private:
  Airframe af_;
  std::vector<Segment> segments_;
  int current_ = -1;
  double segment_start_s_ = 0.0;
  double yaw_at_start_rad_ = 0.0;
  Vec3 p_at_start_W_ = Vec3::Zero();
  Vec3 heading_W_ = Vec3::UnitX();  // horizontal unit vector of body x at the segment's start
};

}  // namespace qswarm
