#pragma once

#include <cstddef>
#include <vector>

#include "common/core/math.hpp"
#include "common/core/topology.hpp"
#include "common/core/tracking_controller.hpp"

namespace qswarm {

// Decentralised collision avoidance: a safety filter on the velocity of an agent's own tracked
// reference (never on its consensus state, so the agreement is untouched).
//
// For each agent j it hears, with n = (p_i - p_j)/d and d = |p_i - p_j|, the barrier
// h_ij = d - D (D = safe distance + margin) must satisfy dh/dt >= -rate h. Each of the two agents
// takes half (reciprocal avoidance, after Wang, Ames and Egerstedt 2017):
//   n . v_i >= -(rate / 2) (d - D)
// so if both hold, dh/dt = n . (v_i - v_j) >= -rate h and h stays >= 0 (d >= D) for velocity-
// controlled agents; inside (d < D) the right side is positive and pushes the two apart. The filter
// returns the velocity closest to the desired one that meets every constraint (an exact QP: 3
// unknowns, so the optimum has at most 3 active constraints and is found by enumeration). Needs
// only the neighbours' positions: the neighbour's own filter covers its half.
//
// Assumed: every agent of the run runs this filter (the runtime turns it on for all or none); a
// neighbour's position is its last sample moved on by the sample's velocity for the sample's age,
// and a neighbour silent past the neighbour timeout is gone. The margin covers what the kinematic
// argument leaves out: the quadcopter tracks its reference with a lag, the reference brakes no
// harder than brake_mps2, and positions are up to a tick old. tests/core/avoidance_test.cpp
// measures the separation with the real dynamics, the tracking controller and 20 ms-old samples.
struct AvoidanceConfig {
  bool enabled = false;
  // Never closer than this, centre to centre. 1 m: the paper's airframe spans 2 x 0.25 m arms
  // plus rotors (about 0.7 m), so two quadcopters 1 m apart keep 0.3 m of air between their tips.
  double safe_distance_m = 1.0;
  // Kept beyond the safe distance by the filter (tracking lag, sample age, braking limit).
  double margin_m = 0.3;
  // The barrier's rate [1/s]: the allowed approach speed is rate (d - D) / 2 per agent.
  double rate_hz = 1.2;
  // The reference may brake this hard to meet a constraint (the airframe's tilt limit allows about
  // g tan(0.45) = 4.7 m/s^2); its comfortable acceleration otherwise is the scenario's limit.
  double brake_mps2 = 4.5;
  void validate() const;
  double filter_distance_m() const { return safe_distance_m + margin_m; }
};

// What the filter knows of a neighbour: where it is now (extrapolated) and who it is.
struct Obstacle {
  AgentId id = 0;
  Vec3 p_W = Vec3::Zero();
};

struct SafeVelocity {
  Vec3 v_W = Vec3::Zero();
  int active = 0;        // constraints that changed the desired velocity
  bool feasible = true;  // false: no velocity meets them all (returned: the least violating)
};

// Where a neighbour is at a time age_s after its last sample: moved on by the sample's velocity for
// at most kMaxProjectionS either way. Past that it is held where it was last seen, not flown on in
// a straight line (a silent neighbour may have stopped, or died). The agents' filters and the
// record's separation use this one rule, so both see a silent neighbour in the same place.
inline constexpr double kMaxProjectionS = 0.1;
Vec3 project_position(const Vec3& p_W, const Vec3& v_W, double age_s);

// The velocity closest to v_des that keeps the barrier for every obstacle (see above), for an
// agent at p_W of id `self`. `goal_W` decides which way to pass: when a neighbour stands between
// the agent and a goal beyond it, the desired velocity is first turned to the agent's right (about
// z), so two agents meeting head-on pass each other instead of stopping nose to nose. Pure.
SafeVelocity safe_velocity(AgentId self, const Vec3& p_W, const Vec3& v_des, const Vec3& goal_W,
                           const std::vector<Obstacle>& others, const AvoidanceConfig& c);

// The reference an agent's quadcopter tracks: it moves toward a goal with bounded speed and
// acceleration so that it stays flyable and, with avoidance, through safe_velocity.
class ReferenceGenerator {
 public:
  ReferenceGenerator(const Vec3& p0_W, double speed_mps, double accel_mps2)
      : p_W_(p0_W), speed_(speed_mps), accel_(accel_mps2) {}

  // Advance by dt toward goal_W. With `avoid` enabled the velocity is filtered against `others`,
  // with the agent's physical position `self_p_W` (what the others see of it).
  TrackingReference step(const Vec3& goal_W, double dt, AgentId self, const Vec3& self_p_W,
                         const std::vector<Obstacle>& others, const AvoidanceConfig& avoid);

 private:
  Vec3 p_W_;
  Vec3 v_W_ = Vec3::Zero();
  double speed_, accel_;
};

}  // namespace qswarm
