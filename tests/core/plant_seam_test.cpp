// The plant seam: every registered plant resolves and starts where its agent does, the point agent
// is where its law puts it, and the quadcopter plant is the paper's controller and dynamics, step
// for step.
#include <gtest/gtest.h>

#include <cmath>

#include "common/core/math.hpp"
#include "common/core/plant.hpp"
#include "common/core/primitives.hpp"
#include "tests/support/error_of.hpp"

namespace qswarm {
namespace {

PlantStart start_at(const Vec3& p, double yaw_rad) {
  PlantStart s;
  s.id = 3;
  s.p0_W = p;
  s.yaw_rad = yaw_rad;
  s.airframe = Airframe::paper();
  return s;
}

TEST(PlantSeam, EveryPlantIsFoundByNameAndAliasAndStartsAtRestWhereItsAgentDoes) {
  for (const PlantSpec& s : registered_plants()) {
    EXPECT_EQ(&find_plant(s.name), &s);
    for (const std::string& a : s.aliases) EXPECT_EQ(&find_plant(a), &s) << a;
    const auto plant = make_plant({s.name, {}}, start_at(Vec3(1, 2, 3), 0.5));
    EXPECT_EQ(plant->position(), Vec3(1, 2, 3)) << s.name;
    EXPECT_EQ(plant->velocity(), Vec3::Zero()) << s.name;
    EXPECT_NEAR(tait_bryan_from_rotation(plant->attitude().toRotationMatrix()).yaw_rad, 0.5, 1e-12)
        << s.name;
  }
  EXPECT_EQ(find_plant("point").name, "particle");
  EXPECT_FALSE(find_plant("particle").follows_reference);
  EXPECT_TRUE(find_plant("quadcopter").oriented);
  EXPECT_EQ(find_plant("quadcopter").min_physics_hz, 500.0);
  EXPECT_NE(error_of([] { find_plant("hexacopter"); }).find("particle, quadcopter"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              resolve_plant_params(find_plant("quadcopter"), {{"mass_kg", 1}});
            }).find("field 'plant_params[\"mass_kg\"]' of plant quadcopter: no such parameter"),
            std::string::npos);
}

TEST(PlantSeam, ThePointAgentIsWhereItsLawPutsIt) {
  const auto plant = make_plant({"particle", {}}, start_at(Vec3(1, 2, 3), 0.0));
  plant->aim(Vec3(4, 5, 6));
  EXPECT_EQ(plant->position(), Vec3(4, 5, 6));
  TrackingReference far;
  far.p_W = Vec3(100, 0, 0);
  plant->step(far, 0.01);  // nothing steps it: it has no dynamics
  EXPECT_EQ(plant->position(), Vec3(4, 5, 6));
  EXPECT_EQ(plant->rotors(), RotorSpeeds::Zero());
}

TEST(PlantSeam, TheQuadcopterPlantIsThePapersControllerAndDynamicsStepForStep) {
  // Given the plant and, beside it, the controller and RK4 called by hand, from one start,
  const PlantStart st = start_at(Vec3(0, 0, 10), 0.3);
  const auto plant = make_plant({"quadcopter", {}}, st);
  QuadState x;
  x.p_W = st.p0_W;
  x.R_WB = rotation_from_tait_bryan({0.0, 0.0, st.yaw_rad});
  EXPECT_EQ(plant->rotors(), hover_rotors(st.airframe));  // it starts hovering
  // when both track a reference that moves away for 4 s at 500 Hz,
  for (int i = 0; i < 2000; ++i) {
    TrackingReference ref;
    ref.p_W = Vec3(0.001 * i, 0.0, 10.0);
    ref.v_W = Vec3(0.5, 0.0, 0.0);
    plant->step(ref, 0.002);
    ref.yaw_rad = st.yaw_rad;  // the plant holds its start's heading
    const RotorSpeeds w = track(st.airframe, st.gains, x, ref).allocation.omega_radps;
    x = rk4_step(st.airframe, x, w, 0.002);
    ASSERT_EQ(plant->rotors(), w) << "step " << i;
  }
  // then they are the same to the bit, and it flew.
  EXPECT_EQ(plant->position(), x.p_W);
  EXPECT_EQ(plant->velocity(), x.velocity_W());
  EXPECT_GT(plant->position().x(), 1.5);
}

TEST(PlantSeam, APointMassTracksAStepWithinItsAccelerationBound) {
  // Given the plant written only through the seam, asked for a 5 m step,
  const auto plant =
      make_plant({"double-integrator", {{"max_accel_mps2", 2.0}}}, start_at(Vec3::Zero(), 0.0));
  TrackingReference ref;
  ref.p_W = Vec3(3, 4, 0);
  Vec3 v_before = Vec3::Zero();
  double max_accel = 0.0, overshoot = 0.0, settled_s = -1.0;
  for (int i = 1; i <= 10000; ++i) {
    plant->step(ref, 0.002);
    max_accel = std::max(max_accel, (plant->velocity() - v_before).norm() / 0.002);
    v_before = plant->velocity();
    overshoot = std::max(overshoot, plant->position().dot(ref.p_W.normalized()) - 5.0);
    const bool inside = (plant->position() - ref.p_W).norm() < 0.01;
    if (inside && settled_s < 0.0) settled_s = i * 0.002;
    if (!inside) settled_s = -1.0;
  }
  // then it never commands more than its bound, and settles there (critically damped: no
  // overshoot beyond the saturation's).
  EXPECT_LE(max_accel, 2.0 + 1e-9);
  EXPECT_GT(settled_s, 0.0);
  EXPECT_LT(overshoot, 0.25);
  EXPECT_EQ(plant->rotors(), RotorSpeeds::Zero());
  EXPECT_FALSE(find_plant("point-mass").oriented);
  // Its parameters are checked by name, like a law's.
  EXPECT_NE(error_of([] {
              make_plant({"point-mass", {{"max_accel_mps2", 0.0}}}, start_at(Vec3::Zero(), 0));
            })
                .find("field 'plant_params[\"max_accel_mps2\"]' of plant point-mass: expected in "
                      "[0.1, 50], got 0"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              make_plant({"point-mass", {{"damping", std::nan("")}}}, start_at(Vec3::Zero(), 0));
            }).find("plant_params[\"damping\"]"),
            std::string::npos);
}

}  // namespace
}  // namespace qswarm
