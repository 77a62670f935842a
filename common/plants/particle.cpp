// The paper's point agent (section 2): its position is its consensus state (its slot about it in a
// formation), with no dynamics between. It keeps its start's heading as its attitude.
#include "common/core/math.hpp"
#include "common/core/plant.hpp"

namespace qswarm::plants {
namespace {

class ParticlePlant final : public Plant {
 public:
  explicit ParticlePlant(const PlantStart& s)
      : p_W_(s.p0_W), q_WB_(rotation_from_tait_bryan({0.0, 0.0, s.yaw_rad})) {}
  void aim(const Vec3& goal_W) override { p_W_ = goal_W; }
  void step(const TrackingReference&, double) override {}
  Vec3 position() const override { return p_W_; }
  Vec3 velocity() const override { return Vec3::Zero(); }
  Eigen::Quaterniond attitude() const override { return q_WB_; }

 private:
  Vec3 p_W_;
  Eigen::Quaterniond q_WB_;
};

}  // namespace

PlantSpec particle() {
  PlantSpec s;
  s.name = "particle";
  s.aliases = {"point"};
  s.summary = "the paper's point agent: it is where its law puts it (section 2)";
  s.follows_reference = false;
  s.make = [](const PlantStart& start) { return std::make_unique<ParticlePlant>(start); };
  return s;
}

}  // namespace qswarm::plants
