// The paper's quadcopter (section 3) and motion primitives (section 4.1).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include <Eigen/SVD>

#include "common/core/allocation.hpp"
#include "common/core/coordinate_form.hpp"
#include "common/core/dynamics.hpp"
#include "common/core/math.hpp"
#include "common/core/primitives.hpp"

namespace qswarm {
namespace {

constexpr double kPi = std::numbers::pi;
const Airframe kPaper = Airframe::paper();

QuadState fly(const Airframe& af, QuadState s, const RotorSpeeds& w, double duration, double dt) {
  const int n = static_cast<int>(std::lround(duration / dt));
  for (int i = 0; i < n; ++i) s = rk4_step(af, s, w, dt);
  return s;
}

TEST(Dynamics, HoverHoldsAtTheHoverRotorSpeed) {
  // Paper (proof of the yaw Lemma): sum t_i = m g, so omega = sqrt(m g / (4 K_r)) = 196.1 rad/s.
  const double expected = std::sqrt(0.468 * 9.81 / (4.0 * 2.9842e-5));
  EXPECT_NEAR(kPaper.hover_rotor_speed_radps(), expected, 1e-12);
  EXPECT_NEAR(expected, 196.11, 0.01);
  const QuadState end = fly(kPaper, QuadState{}, hover_rotors(kPaper), 10.0, 0.002);
  EXPECT_LT(end.p_W.norm(), 1e-9);
  EXPECT_LT(end.v_B.norm(), 1e-9);
  EXPECT_LT(end.omega_B.norm(), 1e-12);
  // 1% more speed climbs: the balance is real, not a fixed point of the code.
  const QuadState up = fly(kPaper, QuadState{}, hover_rotors(kPaper) * 1.01, 2.0, 0.002);
  EXPECT_GT(up.p_W.z(), 0.3);
}

TEST(Dynamics, YawLemmaHoldsPositionWhileYawing) {
  // Yaw Lemma: omega1 = omega3 = sqrt(m g/(2 K_r) - omega2^2), omega4 = omega2, omega2 free.
  for (const double omega2 : {185.0, 190.0, 200.0, 205.0}) {
    const RotorSpeeds w = yaw_lemma_rotors(kPaper, omega2);
    EXPECT_NEAR(total_thrust(kPaper, w), kPaper.weight_N(), 1e-12);
    const QuadState end = fly(kPaper, QuadState{}, w, 1.0, 0.002);  // 1 s: |yaw| stays below pi
    const TaitBryan a = tait_bryan_from_rotation(end.R_WB);
    EXPECT_LT(end.p_W.norm(), 1e-9) << omega2;
    EXPECT_LT(std::abs(a.roll_rad) + std::abs(a.pitch_rad), 1e-12) << omega2;
    // Yaw goes the way of the torque 2 K_d (omega1^2 - omega2^2).
    const double tau_z = 2.0 * kPaper.K_d * (w[0] * w[0] - omega2 * omega2);
    EXPECT_GT(std::abs(a.yaw_rad), 0.05) << omega2;
    EXPECT_EQ(std::signbit(a.yaw_rad), std::signbit(tau_z)) << omega2;
  }
  // The inverse used by the maneuvers gives back the torque asked for.
  const double omega2 = yaw_lemma_omega2_for_torque(kPaper, 2e-3);
  const RotorSpeeds w = yaw_lemma_rotors(kPaper, omega2);
  EXPECT_NEAR(rotor_torque(kPaper, w).z(), 2e-3, 1e-12);
}

TEST(Dynamics, XAxisLemmaRotorsKeepAltitudeAndLeaveAYawTorque) {
  // x-axis Lemma: omega2 = (sqrt((6a - 8 K_r w4^2)/K_r) - w4)/3, omega1 = omega3 = (w2 + w4)/2.
  const double a = kPaper.weight_N();
  for (const double w4 : {190.0, 196.0, 200.0}) {
    const RotorSpeeds w = x_axis_lemma_rotors(kPaper, a, w4);
    EXPECT_NEAR(total_thrust(kPaper, w), a, 1e-12);        // sum t_i = a
    EXPECT_NEAR(rotor_torque(kPaper, w).x(), 0.0, 1e-15);  // omega1 = omega3: no roll torque
    // The yaw torque K_d (w1^2 - w2^2 + w3^2 - w4^2) equals -K_d (w2 - w4)^2 / 2.
    const double yaw = rotor_torque(kPaper, w).z();
    EXPECT_NEAR(yaw, -kPaper.K_d * std::pow(w[1] - w[3], 2) / 2.0, 1e-15);
    EXPECT_NEAR(yaw, x_axis_lemma_yaw_torque(kPaper, w[1], w[3]), 1e-15);
    if (std::abs(w[1] - w[3]) > 1e-6) {
      EXPECT_LT(yaw, 0.0);
    }
  }
  // Quantified at the pitch torque the paper's maneuver peaks at (omega4 - omega2 about 2 rad/s):
  // about -6.5e-7 N m, i.e. a yaw acceleration of -8.4e-5 rad/s^2 that the Lemma neglects.
  const double w4 = x_axis_lemma_omega4_for_torque(kPaper, a, 2.0e-3);
  const RotorSpeeds w = x_axis_lemma_rotors(kPaper, a, w4);
  EXPECT_NEAR(rotor_torque(kPaper, w).y(), 2.0e-3, 1e-9);
  const double yaw = x_axis_lemma_yaw_torque(kPaper, w[1], w[3]);
  EXPECT_LT(yaw, -1e-8);
  EXPECT_GT(yaw, -1e-5);
}

TEST(Dynamics, GeometricAndCoordinateFormsAgreeAwayFromTheSingularity) {
  // drake-style independent check: the hand-written geometric form (R, v, Omega) against the
  // paper's Lemma in Tait-Bryan coordinates, at random states with |theta| <= 1.2 rad.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> rotor(120.0, 300.0);
  for (int trial = 0; trial < 200; ++trial) {
    CoordinateState x;
    x << 10 * u(rng), 10 * u(rng), 10 * u(rng), 3.0 * u(rng), 1.2 * u(rng), 3.0 * u(rng),
        5 * u(rng), 5 * u(rng), 5 * u(rng), 3 * u(rng), 3 * u(rng), 3 * u(rng);
    const RotorSpeeds w(rotor(rng), rotor(rng), rotor(rng), rotor(rng));
    const QuadState s = from_coordinates(x);
    const QuadStateDot geo = derivatives(kPaper, s, w);
    const CoordinateState coord = coordinate_derivatives(kPaper, x, w);
    EXPECT_LT((geo.p_dot_W - coord.segment<3>(0)).norm(), 1e-9) << trial;
    EXPECT_LT((geo.v_dot_B - coord.segment<3>(6)).norm(), 1e-9) << trial;
    EXPECT_LT((geo.omega_dot_B - coord.segment<3>(9)).norm(), 1e-6) << trial;
    // Euler rates: R(eta + h eta_dot) must equal R + h R_dot to first order.
    const double h = 1e-7;
    const Mat3 R_next =
        rotation_from_tait_bryan({x[3] + h * coord[3], x[4] + h * coord[4], x[5] + h * coord[5]});
    EXPECT_LT(((R_next - s.R_WB) / h - geo.R_dot).norm(), 1e-5) << trial;
  }
}

TEST(Dynamics, GeometricAndCoordinateTrajectoriesAgree) {
  // Both forms integrated for 2 s from a tilted, spinning state with unequal rotors.
  CoordinateState x;
  x << 1, 2, 3, 0.3, -0.4, 1.0, 1.0, -0.5, 0.2, 0.4, -0.3, 0.8;
  const RotorSpeeds w(200, 195, 198, 203);
  QuadState s = from_coordinates(x);
  for (int i = 0; i < 2000; ++i) {
    s = rk4_step(kPaper, s, w, 1e-3);
    x = coordinate_rk4_step(kPaper, x, w, 1e-3);
  }
  const QuadState c = from_coordinates(x);
  EXPECT_LT((s.p_W - c.p_W).norm(), 1e-8);
  EXPECT_LT((s.R_WB - c.R_WB).norm(), 1e-8);
  EXPECT_LT((s.omega_B - c.omega_B).norm(), 1e-8);
}

TEST(Dynamics, Rk4IsFourthOrder) {
  // A smooth tumbling, accelerating trajectory; error at t = 1 s against dt = 1e-4.
  QuadState s0;
  s0.v_B = Vec3(1.0, -0.5, 0.3);
  s0.omega_B = Vec3(0.8, -0.6, 1.5);
  const RotorSpeeds w(205, 190, 200, 198);
  const QuadState ref = fly(kPaper, s0, w, 1.0, 1e-4);
  const auto err = [&](double dt) {
    const QuadState s = fly(kPaper, s0, w, 1.0, dt);
    return (s.p_W - ref.p_W).norm() + (s.R_WB - ref.R_WB).norm() + (s.v_B - ref.v_B).norm() +
           (s.omega_B - ref.omega_B).norm();
  };
  const double e1 = err(0.02), e2 = err(0.01), e3 = err(0.005);
  const double order12 = std::log2(e1 / e2), order23 = std::log2(e2 / e3);
  EXPECT_GT(order12, 3.6);
  EXPECT_LT(order12, 4.4);
  EXPECT_GT(order23, 3.6);
  EXPECT_LT(order23, 4.4);
}

TEST(Dynamics, RotationStaysOrthonormal) {
  QuadState s;
  s.omega_B = Vec3(5, -3, 7);
  s = fly(kPaper, s, RotorSpeeds(210, 180, 190, 220), 20.0, 0.002);
  EXPECT_LT((s.R_WB.transpose() * s.R_WB - Mat3::Identity()).norm(), 1e-12);
  EXPECT_NEAR(s.R_WB.determinant(), 1.0, 1e-12);
}

// The fast iteration must give the SVD's polar factor wherever it answers, and hand everything
// it cannot (far off SO(3), reflections, NaN) to the SVD rather than return a non-rotation.
TEST(Dynamics, OrthonormalizeGivesTheSvdsPolarFactor) {
  std::mt19937 rng(20);
  std::normal_distribution<double> n(0.0, 1.0);
  auto svd_polar = [](const Mat3& m) {
    Eigen::JacobiSVD<Mat3> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Mat3 u = svd.matrixU();
    if ((u * svd.matrixV().transpose()).determinant() < 0.0) u.col(2) *= -1.0;
    return Mat3(u * svd.matrixV().transpose());
  };
  for (const double noise : {0.0, 1e-12, 1e-8, 1e-5, 1e-3, 0.3}) {
    for (int i = 0; i < 200; ++i) {
      const Mat3 rot = rotation_from_tait_bryan({n(rng), 0.7 * n(rng), n(rng)});
      Mat3 drift;
      for (int k = 0; k < 9; ++k) drift(k / 3, k % 3) = noise * n(rng);
      const Mat3 m = rot + drift;
      const Mat3 r = orthonormalize(m);
      EXPECT_LT((r.transpose() * r - Mat3::Identity()).cwiseAbs().maxCoeff(), 1e-14) << noise;
      EXPECT_NEAR(r.determinant(), 1.0, 1e-14) << noise;
      EXPECT_LT((r - svd_polar(m)).cwiseAbs().maxCoeff(), 1e-13) << noise;
    }
  }
  Mat3 reflection = Mat3::Identity();
  reflection(2, 2) = -1.0;
  EXPECT_NEAR(orthonormalize(reflection).determinant(), 1.0, 1e-14);
  EXPECT_NEAR(orthonormalize(0.5 * Mat3::Identity()).determinant(), 1.0, 1e-14);
}

TEST(Allocation, InverseOfThePapersAllocationAndRotorLimits) {
  // Round trip where feasible.
  const RotorSpeeds w(190, 200, 205, 195);
  const Allocation back = allocate(kPaper, wrench_from_rotors(kPaper, w));
  EXPECT_FALSE(back.saturated);
  EXPECT_LT((back.omega_radps - w).norm(), 1e-9);
  // Infeasible requests keep every rotor within [min, max], giving up yaw before roll/pitch.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 500; ++i) {
    Wrench req{kPaper.weight_N() * (1.0 + 2.0 * u(rng)),
               Vec3(0.5 * u(rng), 0.5 * u(rng), 0.05 * u(rng))};
    const Allocation a = allocate(kPaper, req);
    EXPECT_TRUE((a.omega_radps.array() >= kPaper.rotor_min_radps - 1e-9).all());
    EXPECT_TRUE((a.omega_radps.array() <= kPaper.rotor_max_radps + 1e-9).all());
  }
  Wrench greedy{kPaper.weight_N(), Vec3(0.05, 0.0, 0.05)};
  const Allocation g = allocate(kPaper, greedy);
  EXPECT_TRUE(g.saturated);
  const Wrench got = wrench_from_rotors(kPaper, g.omega_radps);
  EXPECT_NEAR(got.torque_B_Nm.x(), 0.05, 1e-9);    // roll torque kept...
  EXPECT_LT(std::abs(got.torque_B_Nm.z()), 0.05);  // ...yaw torque given up
}

TEST(Maneuver, PapersSingleAgentFlight) {
  // Paper 4.2.1: rise for 12 s, yaw +pi/2 over 4 s, fly along body x for 4 s (height and distance
  // are not given in the paper: 10 m and 4 m here).
  OpenLoopManeuver m = OpenLoopManeuver::paper_single_agent(kPaper, 10.0, 4.0);
  QuadState s;
  const double dt = 0.002;
  double max_roll = 0.0, max_pitch = 0.0, max_xy_during_climb = 0.0;
  Vec3 after_yaw = Vec3::Zero();
  double yaw_after_yaw = 0.0;
  for (int i = 0; i < 10000; ++i) {
    const double t = i * dt;
    s = rk4_step(kPaper, s, m.command(t, s), dt);
    const TaitBryan a = tait_bryan_from_rotation(s.R_WB);
    max_roll = std::max(max_roll, std::abs(a.roll_rad));
    max_pitch = std::max(max_pitch, std::abs(a.pitch_rad));
    if (t < 12.0) max_xy_during_climb = std::max(max_xy_during_climb, s.p_W.head<2>().norm());
    if (i == 7999) {
      after_yaw = s.p_W;
      yaw_after_yaw = a.yaw_rad;
    }
  }
  const TaitBryan a = tait_bryan_from_rotation(s.R_WB);
  EXPECT_LT(max_xy_during_climb, 1e-9);  // straight up
  EXPECT_NEAR(after_yaw.z(), 10.0, 0.01);
  EXPECT_LT(after_yaw.head<2>().norm(), 1e-6);  // yaw in place
  EXPECT_NEAR(yaw_after_yaw, kPi / 2.0, 1e-3);  // the yaw Lemma segment
  EXPECT_NEAR(a.yaw_rad, kPi / 2.0, 1e-3);
  EXPECT_LT(max_roll, 1e-3);   // roll stays zero (as in the paper's figure)
  EXPECT_GT(max_pitch, 0.05);  // pitch moves it
  // Body x after the yaw is inertial +y: it ends about 4 m along +y at the same height.
  EXPECT_NEAR(s.p_W.y(), 4.0, 0.05);
  EXPECT_NEAR(s.p_W.x(), 0.0, 0.05);
  EXPECT_NEAR(s.p_W.z(), 10.0, 0.05);
}

TEST(Maneuver, XAxisLemmaYawTorqueTurnsTheDroneClockwise) {
  // Body-x flight alone from hover at yaw 0: the rotors of the x-axis Lemma leave the yaw torque
  // K_d(w1^2 - w2^2 + w3^2 - w4^2) = -K_d (w2 - w4)^2 / 2 < 0, so the drone yaws clockwise by
  // about psi = int int tau_z / J3. Measured for 4 m in 4 s: see the printed numbers.
  OpenLoopManeuver m(kPaper, {{OpenLoopManeuver::Kind::kBodyX, 4.0, 4.0}});
  QuadState s;
  const double dt = 0.001;
  double yaw_rate_pred = 0.0, yaw_pred = 0.0, peak_torque = 0.0;
  for (int i = 0; i < 4000; ++i) {
    const RotorSpeeds w = m.command(i * dt, s);
    const double tau_z = x_axis_lemma_yaw_torque(kPaper, w[1], w[3]);
    EXPECT_NEAR(tau_z, rotor_torque(kPaper, w).z(), 1e-15);
    peak_torque = std::min(peak_torque, tau_z);
    yaw_pred += dt * yaw_rate_pred + 0.5 * dt * dt * tau_z / kPaper.inertia_kgm2.z();
    yaw_rate_pred += dt * tau_z / kPaper.inertia_kgm2.z();
    s = rk4_step(kPaper, s, w, dt);
  }
  const double yaw = tait_bryan_from_rotation(s.R_WB).yaw_rad;
  std::printf("x-axis Lemma, 4 m in 4 s: peak yaw torque %.3e N m, yaw %.3e rad (predicted %.3e)\n",
              peak_torque, yaw, yaw_pred);
  EXPECT_LT(peak_torque, 0.0);
  EXPECT_LT(yaw, 0.0);
  EXPECT_NEAR(yaw, yaw_pred, 0.1 * std::abs(yaw_pred));
  EXPECT_NEAR(s.p_W.x(), 4.0, 0.02);
  EXPECT_LT(std::abs(s.p_W.z()), 0.01);
}

TEST(Maneuver, PapersThreeDroneYawThenFlyRendezvous) {
  // Paper 4.2.2: drones at (0,0,0) yaw 0, (0,9,0) yaw -pi/4, (15,9,0) yaw pi/2 meet at (5, 6, 0).
  const Vec3 target(5, 6, 0);
  const std::vector<std::pair<Vec3, double>> starts = {
      {{0, 0, 0}, 0.0}, {{0, 9, 0}, -kPi / 4.0}, {{15, 9, 0}, kPi / 2.0}};
  std::vector<double> flight_times;
  for (const auto& [p0, yaw0] : starts) {
    QuadState s;
    s.p_W = p0;
    s.R_WB = rotation_from_tait_bryan({0, 0, yaw0});
    OpenLoopManeuver m = OpenLoopManeuver::yaw_then_fly(kPaper, s, target);
    flight_times.push_back(m.duration_s());
    const double dt = 0.002;
    double max_roll = 0.0;
    for (double t = 0.0; t < m.duration_s(); t += dt) {
      s = rk4_step(kPaper, s, m.command(t, s), dt);
      max_roll = std::max(max_roll, std::abs(tait_bryan_from_rotation(s.R_WB).roll_rad));
    }
    EXPECT_LT((s.p_W - target).norm(), 0.02) << p0.transpose();
    EXPECT_LT(max_roll, 1e-3);
  }
  // Flight times differ per drone (distances 7.8, 5.8 and 10.4 m).
  EXPECT_NE(flight_times[0], flight_times[1]);
  EXPECT_NE(flight_times[1], flight_times[2]);
}

}  // namespace
}  // namespace qswarm
