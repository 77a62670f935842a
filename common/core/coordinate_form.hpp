#pragma once

#include <Eigen/Dense>

#include "common/core/airframe.hpp"
#include "common/core/dynamics.hpp"

namespace qswarm {

// The paper's coordinate form (Lemma "equations of motion in coordinates"): the state
// eta = (b1, b2, b3, phi, theta, psi, v1, v2, v3, Omega1, Omega2, Omega3). Written term by term
// from the Lemma's twelve equations, independently of dynamics.cpp, so each checks the other.
// Singular at theta = +-pi/2 (the Tait-Bryan chart's edge).
using CoordinateState = Eigen::Matrix<double, 12, 1>;

CoordinateState coordinate_derivatives(const Airframe& af, const CoordinateState& x,
                                       const RotorSpeeds& w);
CoordinateState coordinate_rk4_step(const Airframe& af, const CoordinateState& x,
                                    const RotorSpeeds& w, double dt_s);

CoordinateState to_coordinates(const QuadState& s);
QuadState from_coordinates(const CoordinateState& x);

}  // namespace qswarm
