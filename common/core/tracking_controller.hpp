#pragma once

#include "common/core/airframe.hpp"
#include "common/core/allocation.hpp"
#include "common/core/dynamics.hpp"

namespace qswarm {

// Where the quadcopter should be: position, its derivatives (feed-forward) and heading.
struct TrackingReference {
  Vec3 p_W = Vec3::Zero();
  Vec3 v_W = Vec3::Zero();
  Vec3 a_W = Vec3::Zero();
  double yaw_rad = 0.0;
};

struct TrackingGains {
  double pos_natural_freq_radps = 1.6;  // translational loop
  double pos_damping = 0.9;
  double att_natural_freq_radps = 22.0;  // attitude loop, well inside a 500 Hz physics rate
  double att_damping = 0.8;
  double max_pos_error_m = 2.5;  // position error is saturated: long moves fly at bounded speed
  double max_tilt_rad = 0.45;    // commanded acceleration limited to this tilt
  double max_climb_accel_mps2 = 4.0;
  void validate() const;
};

struct TrackingOutput {
  Wrench wrench;          // what the controller asked for
  Allocation allocation;  // rotor speeds after the inverse allocation and rotor limits
  Mat3 R_desired = Mat3::Identity();
};

// Geometric tracking on SE(3) after Lee, Leok and McClamroch (2010), in the paper's body frame
// (thrust along +z_B, z up): F = m (a_cmd + g e3), f = F . R e3, b3_d = F/|F|; attitude error
// e_R = vee(R_d^T R - R^T R_d)/2, M = -k_R e_R - k_W Omega + Omega x J Omega (cancelling the
// paper's J Omega x Omega). Position error and tilt are saturated so a distant reference is
// approached at bounded speed. Pure: a function of its inputs.
TrackingOutput track(const Airframe& af, const TrackingGains& k, const QuadState& s,
                     const TrackingReference& ref);

}  // namespace qswarm
