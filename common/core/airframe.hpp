#pragma once

#include "common/core/math.hpp"

namespace qswarm {

// Physical parameters of one quadcopter. Defaults are the paper's Table 1 (taken there from Bouadi
// et al.); rotor speed limits are ours: the paper flies open loop and never states them.
struct Airframe {
  double mass_kg = 0.468;                              // m
  Vec3 inertia_kgm2{3.8278e-3, 3.8288e-3, 7.6566e-3};  // J = diag(J1, J2, J3)
  double rotor_inertia_kgm2 = 2.8385e-5;        // bar J_r (rotor inertia about its spin axis)
  double arm_m = 0.25;                          // d, centre of mass to rotor axis
  double K_r = 2.9842e-5;                       // thrust coefficient [N s^2/rad^2]
  Vec3 C_D{5.5670e-4, 5.5670e-4, 6.3540e-4};    // translational drag [N s^2/m^2]
  Vec3 C_tau{5.5670e-4, 5.5670e-4, 6.3540e-4};  // rotational drag [N m s^2/rad^2]
  double K_d = 3.2320e-7;                       // propeller drag (yaw) coefficient [N m s^2/rad^2]
  double gravity_mps2 = 9.81;                   // g
  double rotor_min_radps = 0.0;                 // omega_i lower limit
  double rotor_max_radps = 350.0;  // upper limit: thrust/weight = 3.2 at 350 rad/s with K_r above

  // The paper's parameter table.
  static Airframe paper() { return Airframe{}; }

  // Throws std::invalid_argument naming the first bad field (negative mass, zero inertia, NaN,
  // ...).
  void validate() const;

  // omega = sqrt(m g / (4 K_r)): each rotor's speed at hover (paper, proof of the yaw Lemma).
  double hover_rotor_speed_radps() const;
  double weight_N() const { return mass_kg * gravity_mps2; }
  double max_thrust_N() const { return 4.0 * K_r * rotor_max_radps * rotor_max_radps; }
};

}  // namespace qswarm
