#include "common/core/primitives.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace qswarm {
namespace {

// A rest-to-rest profile: total change `total` over `duration` along the septic smoothstep
// s(x) = 35x^4 - 84x^5 + 70x^6 - 20x^7, whose velocity, acceleration and jerk vanish at both ends,
// so a pitch that follows the acceleration (theta = atan(a/g)) also starts and ends with zero rate.
struct Profile {
  double pos, vel, acc;
};
constexpr double kPeakAccelFactor = 7.5132;  // max s''(x) on [0, 1]
Profile rest_to_rest(double total, double duration, double tau) {
  const double x = std::clamp(tau, 0.0, duration) / duration;
  const double x2 = x * x, x3 = x2 * x, x4 = x3 * x;
  const double s = x4 * (35.0 - 84.0 * x + 70.0 * x2 - 20.0 * x3);
  const double ds = x3 * (140.0 - 420.0 * x + 420.0 * x2 - 140.0 * x3);
  const double dds = x2 * (420.0 - 1680.0 * x + 2100.0 * x2 - 840.0 * x3);
  return {total * s, total * ds / duration, total * dds / (duration * duration)};
}

// Light feedback gains on the one profiled quantity of each primitive.
constexpr double kAngleKp = 36.0;  // [1/s^2]
constexpr double kAngleKd = 12.0;  // [1/s]
constexpr double kClimbKp = 4.0;   // [1/s^2]
constexpr double kClimbKd = 4.0;   // [1/s]
constexpr double kAlongKp = 1.0;   // [1/s^2]
constexpr double kAlongKd = 1.6;   // [1/s]

double pitch_feedforward(double total, double duration, double tau, double g) {
  return std::atan(rest_to_rest(total, duration, tau).acc / g);
}

}  // namespace

RotorSpeeds hover_rotors(const Airframe& af) {
  return RotorSpeeds::Constant(af.hover_rotor_speed_radps());
}

RotorSpeeds yaw_lemma_rotors(const Airframe& af, double omega2) {
  const double w13_sq = af.weight_N() / (2.0 * af.K_r) - omega2 * omega2;
  if (w13_sq < 0.0) throw std::domain_error("yaw Lemma: omega2 too large for m g / (2 K_r)");
  const double w13 = std::sqrt(w13_sq);
  return RotorSpeeds(w13, omega2, w13, omega2);
}

double yaw_lemma_omega2_for_torque(const Airframe& af, double tau_z) {
  const double w2_sq = 0.5 * (af.weight_N() / (2.0 * af.K_r) - tau_z / (2.0 * af.K_d));
  return std::sqrt(std::clamp(w2_sq, 0.0, af.weight_N() / (2.0 * af.K_r)));
}

RotorSpeeds x_axis_lemma_rotors(const Airframe& af, double a, double omega4) {
  const double radicand = (6.0 * a - 8.0 * af.K_r * omega4 * omega4) / af.K_r;
  if (radicand < 0.0) throw std::domain_error("x-axis Lemma: 6a - 8 K_r omega4^2 < 0");
  const double w2 = (std::sqrt(radicand) - omega4) / 3.0;
  const double w13 = 0.5 * (w2 + omega4);
  return RotorSpeeds(w13, w2, w13, omega4);
}

double x_axis_lemma_thrust(const Airframe& af, const QuadState& s) {
  const double m = af.mass_kg, g = af.gravity_mps2;
  const TaitBryan ang = tait_bryan_from_rotation(s.R_WB);
  const double Ct = std::cos(ang.pitch_rad), St = std::sin(ang.pitch_rad);
  const double v1 = s.v_B.x(), v2 = s.v_B.y(), v3 = s.v_B.z();
  const double O2 = s.omega_B.y(), O3 = s.omega_B.z();
  const double v1_dot = v2 * O3 - v3 * O2 - v1 * std::abs(v1) * af.C_D[0] / m + g * St;
  return m * ((v1_dot * St + v1 * Ct * O2 + v3 * St * O2) / Ct - v1 * O2 + g * Ct) +
         v3 * std::abs(v3) * af.C_D[2];
}

double x_axis_lemma_omega4_for_torque(const Airframe& af, double a, double tau_y) {
  // K_r d (w4^2 - w2(w4)^2) rises monotonically from -2ad/3 (w4 = 0) to +2ad/3 (w2 = 0).
  double lo = 0.0, hi = std::sqrt(2.0 * a / (3.0 * af.K_r));
  const auto torque = [&](double w4) {
    const RotorSpeeds w = x_axis_lemma_rotors(af, a, w4);
    return af.K_r * af.arm_m * (w[3] * w[3] - w[1] * w[1]);
  };
  for (int it = 0; it < 80; ++it) {
    const double mid = 0.5 * (lo + hi);
    (torque(mid) < tau_y ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double x_axis_lemma_yaw_torque(const Airframe& af, double omega2, double omega4) {
  const double w13 = 0.5 * (omega2 + omega4);
  return af.K_d * (2.0 * w13 * w13 - omega2 * omega2 - omega4 * omega4);
}

OpenLoopManeuver::OpenLoopManeuver(Airframe af, std::vector<Segment> segments)
    : af_(std::move(af)), segments_(std::move(segments)) {
  af_.validate();
  for (const Segment& seg : segments_) {
    if (!(seg.duration_s > 0.0) || !std::isfinite(seg.amount)) {
      throw std::invalid_argument("maneuver segment: duration must be > 0 and amount finite");
    }
  }
}

OpenLoopManeuver OpenLoopManeuver::paper_single_agent(const Airframe& af, double climb_m,
                                                      double forward_m) {
  return OpenLoopManeuver(af, {{Kind::kClimb, 12.0, climb_m},
                               {Kind::kYaw, 4.0, std::numbers::pi / 2.0},
                               {Kind::kBodyX, 4.0, forward_m}});
}

OpenLoopManeuver OpenLoopManeuver::yaw_then_fly(const Airframe& af, const QuadState& start,
                                                const Vec3& target, double yaw_duration_s,
                                                double max_pitch_rad) {
  const Vec3 d = target - start.p_W;
  const double distance = std::hypot(d.x(), d.y());
  const double yaw0 = tait_bryan_from_rotation(start.R_WB).yaw_rad;
  const double dyaw = wrap_angle(std::atan2(d.y(), d.x()) - yaw0);
  // Peak acceleration 7.51 D / T^2 = g tan(max pitch) fixes the flight time; times differ per drone
  // as in the paper's figure.
  const double fly_s = std::max(
      1.0, std::sqrt(kPeakAccelFactor * distance / (af.gravity_mps2 * std::tan(max_pitch_rad))));
  return OpenLoopManeuver(af, {{Kind::kYaw, yaw_duration_s, dyaw},
                               {Kind::kBodyX, fly_s, distance},
                               {Kind::kHover, 2.0, 0.0}});
}

double OpenLoopManeuver::duration_s() const {
  double total = 0.0;
  for (const Segment& seg : segments_) total += seg.duration_s;
  return total;
}

RotorSpeeds OpenLoopManeuver::command(double t, const QuadState& s) {
  // Find the segment for t; remember where each segment began (the profiles are relative to it).
  double start = 0.0;
  int index = static_cast<int>(segments_.size());
  for (int i = 0; i < static_cast<int>(segments_.size()); ++i) {
    if (t < start + segments_[i].duration_s) {
      index = i;
      break;
    }
    start += segments_[i].duration_s;
  }
  if (index >= static_cast<int>(segments_.size())) return hover_rotors(af_);
  if (index != current_) {
    current_ = index;
    segment_start_s_ = start;
    yaw_at_start_rad_ = tait_bryan_from_rotation(s.R_WB).yaw_rad;
    p_at_start_W_ = s.p_W;
    const Vec3 x_W = s.R_WB.col(0);
    heading_W_ = Vec3(x_W.x(), x_W.y(), 0.0).normalized();
  }
  const Segment& seg = segments_[index];
  const double tau = t - segment_start_s_;
  const Airframe& af = af_;
  const Vec3 v_W = s.velocity_W();

  switch (seg.kind) {
    case Kind::kHover:
      return hover_rotors(af);
    case Kind::kClimb: {
      // Equal rotors (no torque, no gyroscopic term): thrust = m (g + z'') + drag.
      const Profile p = rest_to_rest(seg.amount, seg.duration_s, tau);
      const double z_acc =
          p.acc + kClimbKp * (p_at_start_W_.z() + p.pos - s.p_W.z()) + kClimbKd * (p.vel - v_W.z());
      const double thrust =
          af.mass_kg * (af.gravity_mps2 + z_acc) + s.v_B.z() * std::abs(s.v_B.z()) * af.C_D[2];
      return RotorSpeeds::Constant(std::sqrt(std::max(0.0, thrust) / (4.0 * af.K_r)));
    }
    case Kind::kYaw: {
      // Yaw Lemma; the free omega2 sets the yaw torque that follows the yaw profile.
      const Profile p = rest_to_rest(seg.amount, seg.duration_s, tau);
      const double yaw = tait_bryan_from_rotation(s.R_WB).yaw_rad;
      const double err = wrap_angle(yaw_at_start_rad_ + p.pos - yaw);
      const double yaw_acc = p.acc + kAngleKp * err + kAngleKd * (p.vel - s.omega_B.z());
      const double O3 = s.omega_B.z();
      const double tau_z = af.inertia_kgm2.z() * yaw_acc + O3 * std::abs(O3) * af.C_tau.z();
      return yaw_lemma_rotors(af, yaw_lemma_omega2_for_torque(af, tau_z));
    }
    case Kind::kBodyX: {
      // x-axis Lemma: thrust a from the state; the free omega4 sets the pitch torque that follows a
      // pitch profile whose horizontal acceleration g tan(theta) flies the rest-to-rest distance.
      const Profile p = rest_to_rest(seg.amount, seg.duration_s, tau);
      const double along = heading_W_.dot(s.p_W - p_at_start_W_);
      const double along_v = heading_W_.dot(v_W);
      const double correction = kAlongKp * (p.pos - along) + kAlongKd * (p.vel - along_v);
      constexpr double h = 1e-3;
      const double th_ff = pitch_feedforward(seg.amount, seg.duration_s, tau, af.gravity_mps2);
      const double th_ff_dot =
          (pitch_feedforward(seg.amount, seg.duration_s, tau + h, af.gravity_mps2) -
           pitch_feedforward(seg.amount, seg.duration_s, tau - h, af.gravity_mps2)) /
          (2.0 * h);
      const double th_ff_ddot =
          (pitch_feedforward(seg.amount, seg.duration_s, tau + h, af.gravity_mps2) - 2.0 * th_ff +
           pitch_feedforward(seg.amount, seg.duration_s, tau - h, af.gravity_mps2)) /
          (h * h);
      const double th_cmd = th_ff + std::atan(correction / af.gravity_mps2);
      const double pitch = tait_bryan_from_rotation(s.R_WB).pitch_rad;
      const double O2 = s.omega_B.y();
      const double pitch_acc =
          th_ff_ddot + kAngleKp * (th_cmd - pitch) + kAngleKd * (th_ff_dot - O2);
      const double tau_y = af.inertia_kgm2.y() * pitch_acc + O2 * std::abs(O2) * af.C_tau.y();
      const double a = x_axis_lemma_thrust(af, s);
      return x_axis_lemma_rotors(af, a, x_axis_lemma_omega4_for_torque(af, a, tau_y));
    }
  }
  return hover_rotors(af);
}

}  // namespace qswarm
