#include "common/core/math.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace qswarm {

namespace {
Mat3 polar_by_svd(const Mat3& r) {
  Eigen::JacobiSVD<Mat3> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 u = svd.matrixU();
  const Mat3& v = svd.matrixV();
  if ((u * v.transpose()).determinant() < 0.0) u.col(2) *= -1.0;
  return u * v.transpose();
}
}  // namespace

Mat3 orthonormalize(const Mat3& r) {
  // An integration step leaves R within about h^5 of SO(3). There the Newton-Schulz iteration
  // X <- X (3I - X'X) / 2 converges quadratically to the same polar factor the SVD gives, at a
  // fraction of its cost (two 3x3 products a round). Far from SO(3) (a reflection, a degenerate
  // matrix, a large error) it may not converge, so the SVD stays the fallback.
  Mat3 x = r;
  for (int round = 0; round < 5; ++round) {
    const Mat3 e = x.transpose() * x - Mat3::Identity();
    const double err = e.cwiseAbs().maxCoeff();
    if (!(err < 1e-3)) break;  // also NaN
    if (err < 1e-14) {
      if (x.determinant() > 0.0) return x;
      break;
    }
    x -= 0.5 * x * e;
  }
  return polar_by_svd(r);
}

Mat3 rotation_from_tait_bryan(const TaitBryan& a) {
  return (Eigen::AngleAxisd(a.yaw_rad, Vec3::UnitZ()) *
          Eigen::AngleAxisd(a.pitch_rad, Vec3::UnitY()) *
          Eigen::AngleAxisd(a.roll_rad, Vec3::UnitX()))
      .toRotationMatrix();
}

TaitBryan tait_bryan_from_rotation(const Mat3& r) {
  TaitBryan a;
  a.pitch_rad = -std::asin(std::clamp(r(2, 0), -1.0, 1.0));
  a.roll_rad = std::atan2(r(2, 1), r(2, 2));
  a.yaw_rad = std::atan2(r(1, 0), r(0, 0));
  return a;
}

double wrap_angle(double a) {
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  a = std::fmod(a + std::numbers::pi, kTwoPi);
  if (a <= 0.0) a += kTwoPi;
  return a - std::numbers::pi;
}

}  // namespace qswarm
