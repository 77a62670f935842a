// The paper's quadcopter (section 3): rigid-body dynamics with drag, integrated by RK4 at the
// physics rate, flown by the geometric tracking controller (its thrust and torques allocated to
// the four rotors) along the reference, which the runtime moves toward the law's goal within
// speed and acceleration limits and filters against collisions.
#include "common/core/math.hpp"
#include "common/core/plant.hpp"
#include "common/core/primitives.hpp"

namespace qswarm::plants {
namespace {

class QuadcopterPlant final : public Plant {
 public:
  explicit QuadcopterPlant(const PlantStart& s)
      : af_(s.airframe), gains_(s.gains), yaw_rad_(s.yaw_rad), rotors_(hover_rotors(af_)) {
    x_.p_W = s.p0_W;
    x_.R_WB = rotation_from_tait_bryan({0.0, 0.0, s.yaw_rad});
  }
  void step(const TrackingReference& ref, double dt_s) override {
    TrackingReference r = ref;
    r.yaw_rad = yaw_rad_;  // it keeps its start's heading
    rotors_ = track(af_, gains_, x_, r).allocation.omega_radps;
    x_ = rk4_step(af_, x_, rotors_, dt_s);
  }
  Vec3 position() const override { return x_.p_W; }
  Vec3 velocity() const override { return x_.velocity_W(); }
  Eigen::Quaterniond attitude() const override { return Eigen::Quaterniond(x_.R_WB); }
  RotorSpeeds rotors() const override { return rotors_; }

 private:
  Airframe af_;
  TrackingGains gains_;
  double yaw_rad_;
  QuadState x_;
  RotorSpeeds rotors_;
};

}  // namespace

PlantSpec quadcopter() {
  PlantSpec s;
  s.name = "quadcopter";
  s.summary = "the paper's quadcopter (section 3) under the tracking controller, RK4";
  s.oriented = true;
  s.airframe = true;
  // RK4 of the attitude loop (22 rad/s natural frequency) and the rotors' allocation.
  s.min_physics_hz = 500.0;
  s.make = [](const PlantStart& start) { return std::make_unique<QuadcopterPlant>(start); };
  return s;
}

}  // namespace qswarm::plants
