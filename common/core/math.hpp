#pragma once

#include <Eigen/Dense>

namespace qswarm {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Vec4 = Eigen::Vector4d;

// The hat map of the paper (section 3.1): hat(y) * z == y.cross(z).
inline Mat3 hat(const Vec3& y) {
  Mat3 m;
  m << 0.0, -y.z(), y.y(), y.z(), 0.0, -y.x(), -y.y(), y.x(), 0.0;
  return m;
}

// Inverse of hat on the skew-symmetric part of a matrix.
inline Vec3 vee(const Mat3& s) {
  return Vec3(0.5 * (s(2, 1) - s(1, 2)), 0.5 * (s(0, 2) - s(2, 0)), 0.5 * (s(1, 0) - s(0, 1)));
}

// Nearest rotation (polar factor) to a matrix that has drifted off SO(3) by integration error.
Mat3 orthonormalize(const Mat3& r);

// Tait-Bryan angles of the paper (intrinsic z-y'-x''): R = R3(psi) R2(theta) R1(phi).
struct TaitBryan {
  double roll_rad = 0.0;   // phi
  double pitch_rad = 0.0;  // theta, in (-pi/2, pi/2)
  double yaw_rad = 0.0;    // psi
};

Mat3 rotation_from_tait_bryan(const TaitBryan& a);
TaitBryan tait_bryan_from_rotation(const Mat3& r_WB);

// Wraps an angle to (-pi, pi].
double wrap_angle(double a_rad);

}  // namespace qswarm
