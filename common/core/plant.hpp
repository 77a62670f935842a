#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "common/core/agent.hpp"
#include "common/core/airframe.hpp"
#include "common/core/dynamics.hpp"
#include "common/core/seam_params.hpp"
#include "common/core/tracking_controller.hpp"

namespace qswarm {

// The plant seam: the vehicle an agent flies. Its law gives it a goal (its slot about its
// consensus estimate) at every consensus tick; a plant that follows a reference gets, at every
// physics step, the goal through the reference's speed and acceleration limits and collision
// avoidance (the runtime's, between the law and the plant), and tracks it with its own controller.
// One file per plant in common/plants/, registered by one line of common/plants/plants.inc.
class Plant {
 public:
  virtual ~Plant() = default;
  // The law's goal: at the start and after every consensus tick. A plant that is where its law
  // puts it (PlantSpec::follows_reference false) moves there now.
  virtual void aim(const Vec3& goal_W) { (void)goal_W; }
  // One physics step of dt_s tracking `ref` (only plants that follow a reference are stepped).
  virtual void step(const TrackingReference& ref, double dt_s) = 0;
  virtual Vec3 position() const = 0;
  virtual Vec3 velocity() const = 0;
  // Body to world; a plant without an attitude keeps the start's heading.
  virtual Eigen::Quaterniond attitude() const = 0;
  // What its samples carry as rotor speeds (zero for a plant without rotors).
  virtual RotorSpeeds rotors() const { return RotorSpeeds::Zero(); }
};

// What a plant starts from: the agent, its start pose, the scenario's airframe and controller
// gains (a plant may ignore them) and its own parameters, resolved.
struct PlantStart {
  AgentId id = 0;
  Vec3 p0_W = Vec3::Zero();
  double yaw_rad = 0.0;
  Airframe airframe;
  TrackingGains gains;
  std::map<std::string, double> params;
};

// A plant as the rest of the project sees it, from one file (common/plants/) and one line of
// common/plants/plants.inc.
struct PlantSpec {
  std::string name;                  // as scenarios and the record spell it: "quadcopter"
  std::vector<std::string> aliases;  // other spellings accepted
  std::string summary;               // one line for `swarm plants` and `swarm inspect`
  std::vector<SeamParam> params;     // named in a scenario's `plant_params`
  // It flies toward its goal, stepped at the physics rate: collision avoidance applies (on by
  // default) and the record measures its own position. False: it is where its law puts it (the
  // paper's point agent), avoidance is refused and nothing is stepped.
  bool follows_reference = true;
  // Its samples carry an attitude and four rotor speeds: the record and the live view draw its
  // heading, `swarm plot` its attitude and rotors (wire and record field `mode` = 1).
  bool oriented = false;
  double min_physics_hz = 0.0;  // a slower rates.physics_hz is refused (its integration's step)
  // It flies the scenario's airframe: the safe distance must clear two of its arm spans.
  bool airframe = false;
  // The largest acceleration it follows, from its parameters; unset: unbounded here (the
  // quadcopter's thrust-to-weight of 3.2 is checked by its airframe). The resolver refuses a run
  // whose reference asks more (limits.reference_accel_mps2, and avoidance's braking when on):
  // a plant that cannot follow the filtered reference would break the safe distance.
  std::function<double(const std::map<std::string, double>&)> max_accel_mps2;
  std::function<std::unique_ptr<Plant>(const PlantStart&)> make;
};

// What a run's agents fly: a plant by name or alias, and its parameters (resolve_plant_params
// completes them).
struct PlantConfig {
  std::string name = "particle";
  std::map<std::string, double> params;
};

// Every registered plant, in the order of common/plants/plants.inc.
const std::vector<PlantSpec>& registered_plants();
// The plant named `name` (or one of its aliases); throws std::invalid_argument naming the plants
// there are.
const PlantSpec& find_plant(const std::string& name);
// "particle, quadcopter, ..." for messages.
std::string plant_names();
// Every parameter of `spec`, the given ones checked (std::invalid_argument naming
// plant_params["name"]), the rest at their fallback.
std::map<std::string, double> resolve_plant_params(const PlantSpec& spec,
                                                   const std::map<std::string, double>& given);
// The plant cfg names, started at `start` with cfg's parameters checked and completed.
std::unique_ptr<Plant> make_plant(const PlantConfig& cfg, PlantStart start);

}  // namespace qswarm
