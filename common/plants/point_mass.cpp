// A point mass with bounded acceleration (a double integrator: p'' = u, |u| <= max_accel_mps2), the
// second-order agent of the consensus literature (Ren and Beard, "Distributed Consensus in
// Multi-vehicle Cooperative Control", 2008, ch. 4) and a first model of a ground robot or a blimp.
// It tracks the reference (the law's goal through the reference's limits and collision avoidance)
// with a PD law on position and velocity plus the reference's acceleration, integrated by
// semi-implicit Euler at the physics rate. It has no attitude: its samples carry a position and
// velocity, as the point agent's do.
//
// Written only through the plant seam (docs/laws.md#write-your-own-plant): this file and one line
// in plants.inc.
#include "common/core/math.hpp"
#include "common/core/plant.hpp"

namespace qswarm::plants {
namespace {

class PointMassPlant final : public Plant {
 public:
  explicit PointMassPlant(const PlantStart& s)
      : p_W_(s.p0_W),
        heading_(rotation_from_tait_bryan({0.0, 0.0, s.yaw_rad})),
        w_(s.params.at("natural_freq_radps")),
        zeta_(s.params.at("damping")),
        a_max_(s.params.at("max_accel_mps2")) {}
  void step(const TrackingReference& ref, double dt_s) override {
    Vec3 u = ref.a_W + w_ * w_ * (ref.p_W - p_W_) + 2.0 * zeta_ * w_ * (ref.v_W - v_W_);
    if (const double n = u.norm(); n > a_max_) u *= a_max_ / n;
    v_W_ += u * dt_s;
    p_W_ += v_W_ * dt_s;
  }
  Vec3 position() const override { return p_W_; }
  Vec3 velocity() const override { return v_W_; }
  Eigen::Quaterniond attitude() const override { return heading_; }

 private:
  Vec3 p_W_;
  Vec3 v_W_ = Vec3::Zero();
  Eigen::Quaterniond heading_;
  double w_, zeta_, a_max_;
};

}  // namespace

PlantSpec point_mass() {
  PlantSpec s;
  s.name = "point-mass";
  s.aliases = {"double-integrator"};
  s.summary = "a point mass with bounded acceleration under a PD law (a double integrator)";
  s.params = {
      {"natural_freq_radps", 0.1, 20.0, 2.0, false, "the tracking loop's natural frequency, rad/s"},
      {"damping", 0.1, 3.0, 1.0, false, "the tracking loop's damping ratio"},
      {"max_accel_mps2", 0.1, 50.0, 6.0, false, "the largest acceleration it commands, m/s^2"}};
  // Semi-implicit Euler of the PD loop rings once 2 damping natural_freq dt passes 1 and diverges
  // past 2: at 150 Hz it stays below 0.8 for every damping and frequency the ranges allow.
  s.min_physics_hz = 150.0;
  s.max_accel_mps2 = [](const std::map<std::string, double>& p) { return p.at("max_accel_mps2"); };
  s.make = [](const PlantStart& start) { return std::make_unique<PointMassPlant>(start); };
  return s;
}

}  // namespace qswarm::plants
