// Closed-loop tracking on SE(3) with the inverse allocation and rotor limits.
#include <gtest/gtest.h>

#include <cmath>

#include "common/core/primitives.hpp"
#include "common/core/tracking_controller.hpp"

namespace qswarm {
namespace {

const Airframe kPaperAirframe = Airframe::paper();

TEST(TrackingController, FliesFromRestToAPointTenMetresAwayAndSettles) {
  // Given a quadcopter at rest at the origin and a reference 10 m away (6, 8, 0) with yaw 1 rad,
  // when the controller flies it at 500 Hz for 20 s,
  QuadState s;
  TrackingReference ref;
  ref.p_W = Vec3(6, 8, 0);
  ref.yaw_rad = 1.0;
  const TrackingGains gains;
  const Vec3 dir = ref.p_W.normalized();
  const double dt = 0.002;
  double max_along = 0.0, max_cross = 0.0, max_alt_err = 0.0;
  double settle_time = -1.0;
  for (int i = 0; i < 10000; ++i) {
    const TrackingOutput out = track(kPaperAirframe, gains, s, ref);
    // rotor limits hold on every command
    ASSERT_TRUE((out.allocation.omega_radps.array() >= kPaperAirframe.rotor_min_radps).all());
    ASSERT_TRUE((out.allocation.omega_radps.array() <= kPaperAirframe.rotor_max_radps).all());
    s = rk4_step(kPaperAirframe, s, out.allocation.omega_radps, dt);
    ASSERT_TRUE(s.finite());
    max_along = std::max(max_along, s.p_W.dot(dir));
    max_cross = std::max(max_cross, (s.p_W - s.p_W.dot(dir) * dir).norm());
    max_alt_err = std::max(max_alt_err, std::abs(s.p_W.z()));
    const bool inside = (s.p_W - ref.p_W).norm() < 0.05;
    if (inside && settle_time < 0.0) settle_time = i * dt;
    if (!inside) settle_time = -1.0;
  }
  // then it settles within 5 cm and stays, with overshoot under 5% of the distance, a straight
  // path, little altitude loss, and the commanded heading.
  std::printf(
      "10 m step: overshoot %.3f m, cross-track %.3f m, altitude error %.3f m, settled at %.2f s\n",
      max_along - 10.0, max_cross, max_alt_err, settle_time);
  EXPECT_GE(settle_time, 0.0);
  EXPECT_LT(settle_time, 15.0);
  EXPECT_LT(max_along - 10.0, 0.5);
  EXPECT_LT(max_cross, 0.1);  // measured 6 cm: it yaws 1 rad while translating
  EXPECT_LT(max_alt_err, 0.3);
  EXPECT_NEAR(tait_bryan_from_rotation(s.R_WB).yaw_rad, 1.0, 1e-3);
  EXPECT_LT(s.velocity_W().norm(), 1e-3);
}

TEST(TrackingController, RecoversFromATumbleWithinRotorLimits) {
  QuadState s;
  s.R_WB = rotation_from_tait_bryan({0.8, -0.6, 2.0});
  s.omega_B = Vec3(4, -3, 2);
  TrackingReference ref;
  bool saturated_once = false;
  for (int i = 0; i < 5000; ++i) {
    const TrackingOutput out = track(kPaperAirframe, TrackingGains{}, s, ref);
    saturated_once |= out.allocation.saturated;
    s = rk4_step(kPaperAirframe, s, out.allocation.omega_radps, 0.002);
  }
  EXPECT_TRUE(saturated_once);  // the limits were actually exercised
  EXPECT_LT(s.p_W.norm(), 0.05);
  EXPECT_LT(s.omega_B.norm(), 1e-3);
}

TEST(TrackingController, FollowsAMovingReference) {
  // A reference moving at 1 m/s along x (as a consensus state would), with velocity feed-forward.
  QuadState s;
  double worst = 0.0;
  for (int i = 0; i < 7500; ++i) {
    const double t = i * 0.002;
    TrackingReference ref;
    ref.p_W = Vec3(t, 0.0, 0.0);
    ref.v_W = Vec3(1.0, 0.0, 0.0);
    s = rk4_step(kPaperAirframe, s,
                 track(kPaperAirframe, TrackingGains{}, s, ref).allocation.omega_radps, 0.002);
    if (t > 5.0) worst = std::max(worst, (s.p_W - ref.p_W).norm());
  }
  EXPECT_LT(worst, 0.05);
}

}  // namespace
}  // namespace qswarm
