#include "common/core/avoidance.hpp"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Dense>

namespace qswarm {
namespace {

// Constraints in the QP at a time (its enumeration grows with the cube of the count): those that
// press hardest on the desired velocity, with any other the answer breaks swapped in.
constexpr std::size_t kMaxConstraints = 8;

struct Halfspace {  // a . v >= b
  Vec3 a;
  double b;
};

Vec3 clamp_norm(const Vec3& v, double max) {
  const double n = v.norm();
  return n > max ? Vec3(v * (max / n)) : v;
}

double worst_violation(const std::vector<Halfspace>& hs, const Vec3& v) {
  double worst = 0.0;
  for (const Halfspace& h : hs) worst = std::max(worst, h.b - h.a.dot(v));
  return worst;
}

// The point closest to u on the plane(s) a_k . v = b_k, or false when they are degenerate (parallel
// normals). Fixed-size closed forms: no allocation inside the QP's enumeration.
bool project_on_planes(const Halfspace* const* h, int m, const Vec3& u, Vec3& out) {
  if (m == 1) {
    const double aa = h[0]->a.squaredNorm();
    if (aa < 1e-18) return false;
    out = u + h[0]->a * ((h[0]->b - h[0]->a.dot(u)) / aa);
    return true;
  }
  if (m == 2) {
    const Vec3& a0 = h[0]->a;
    const Vec3& a1 = h[1]->a;
    const double g00 = a0.squaredNorm(), g01 = a0.dot(a1), g11 = a1.squaredNorm();
    const double det = g00 * g11 - g01 * g01;
    if (std::abs(det) < 1e-12) return false;
    const double r0 = h[0]->b - a0.dot(u), r1 = h[1]->b - a1.dot(u);
    const double l0 = (g11 * r0 - g01 * r1) / det, l1 = (g00 * r1 - g01 * r0) / det;
    out = u + a0 * l0 + a1 * l1;
    return true;
  }
  Mat3 A;
  A.row(0) = h[0]->a.transpose();
  A.row(1) = h[1]->a.transpose();
  A.row(2) = h[2]->a.transpose();
  if (std::abs(A.determinant()) < 1e-9) return false;
  out = A.inverse() * Vec3(h[0]->b, h[1]->b, h[2]->b);
  return out.allFinite();
}

// Exact QP: min |v - u|^2 over the halfspaces hs. The optimum lies on the intersection of at most
// 3 active planes; every feasible candidate is at least as far from u as the optimum, so the
// nearest feasible candidate is the optimum. When none is feasible, the least violating candidate
// (or 0, if that violates less) and feasible = false.
void solve_qp(const std::vector<Halfspace>& hs, const Vec3& u, SafeVelocity& out) {
  const std::size_t m = hs.size();
  double best = std::numeric_limits<double>::infinity();
  double least_violation = std::numeric_limits<double>::infinity();
  Vec3 least_violating = Vec3::Zero();
  out.feasible = true;
  const auto consider = [&](std::initializer_list<const Halfspace*> idx) {
    Vec3 v;
    if (!project_on_planes(idx.begin(), static_cast<int>(idx.size()), u, v)) return;
    const double viol = worst_violation(hs, v);
    if (viol <= 1e-9) {
      const double cost = (v - u).squaredNorm();
      if (cost < best) {
        best = cost;
        out.v_W = v;
        out.active = static_cast<int>(idx.size());
      }
    } else if (viol < least_violation) {
      least_violation = viol;
      least_violating = v;
    }
  };
  // Every feasible point is at least as far from u as the largest single violation (the distance
  // to that halfspace), so a feasible projection onto the most violated plane is the optimum.
  std::size_t worst = 0;
  for (std::size_t i = 1; i < m; ++i)
    if (hs[i].b - hs[i].a.dot(u) > hs[worst].b - hs[worst].a.dot(u)) worst = i;
  consider({&hs[worst]});
  if (std::isfinite(best)) return;
  for (std::size_t i = 0; i < m; ++i) {
    consider({&hs[i]});
    for (std::size_t j = i + 1; j < m; ++j) {
      consider({&hs[i], &hs[j]});
      for (std::size_t k = j + 1; k < m; ++k) consider({&hs[i], &hs[j], &hs[k]});
    }
  }
  if (!std::isfinite(best)) {
    out.feasible = false;
    out.v_W = worst_violation(hs, Vec3::Zero()) < least_violation ? Vec3::Zero() : least_violating;
    out.active = static_cast<int>(m);
  }
}

}  // namespace

void AvoidanceConfig::validate() const {
  const auto positive = [](double v, const char* name, double max) {
    if (!std::isfinite(v) || v <= 0.0 || v > max) {
      throw std::invalid_argument(std::string("avoidance.") + name + " = " + std::to_string(v) +
                                  ": expected a value in (0, " + std::to_string(max) + "]");
    }
  };
  positive(safe_distance_m, "safe_distance_m", 100.0);
  if (!std::isfinite(margin_m) || margin_m < 0.0 || margin_m > 100.0)
    throw std::invalid_argument("avoidance.margin_m = " + std::to_string(margin_m) +
                                ": expected a value in [0, 100]");
  positive(rate_hz, "rate_hz", 100.0);
  positive(brake_mps2, "brake_mps2", 100.0);
}

Vec3 project_position(const Vec3& p_W, const Vec3& v_W, double age_s) {
  return p_W + v_W * std::clamp(age_s, -kMaxProjectionS, kMaxProjectionS);
}

SafeVelocity safe_velocity(AgentId self, const Vec3& p_W, const Vec3& v_des, const Vec3& goal_W,
                           const std::vector<Obstacle>& others, const AvoidanceConfig& c) {
  SafeVelocity out;
  out.v_W = v_des;
  if (!p_W.allFinite() || !v_des.allFinite() || !goal_W.allFinite()) {
    out.v_W = Vec3::Zero();  // nothing sensible to filter: hold still
    out.feasible = false;
    return out;
  }
  const double D = c.filter_distance_m();
  const double speed = v_des.norm();
  // The constraints that can bind: the allowed approach speed rate (d - D) / 2 is below the
  // desired speed (or negative: inside, pushed apart).
  struct Near {
    AgentId id;
    double d;
    Halfspace h;
  };
  std::vector<Near> near;
  for (const Obstacle& o : others) {
    if (o.id == self) continue;
    Vec3 n = p_W - o.p_W;
    double d = n.norm();
    if (!std::isfinite(d)) continue;
    if (0.5 * c.rate_hz * (d - D) > speed + 1e-9) continue;
    if (d > 1e-9) {
      n /= d;
    } else {  // on top of each other: split along x, the lower id to -x
      n = self < o.id ? Vec3(-1, 0, 0) : Vec3(1, 0, 0);
      d = 0.0;
    }
    near.push_back({o.id, d, {n, -0.5 * c.rate_hz * (d - D)}});
  }
  if (near.empty()) return out;

  // Pass on the right: a neighbour between the agent and a goal beyond it turns the desired
  // velocity by the part the constraint would remove, sideways (right of the heading, about z).
  Vec3 u = v_des;
  for (const Near& n : near) {
    const double deficit = n.h.b - n.h.a.dot(v_des);
    if (deficit <= 0.0) continue;
    if ((goal_W - p_W).dot(-n.h.a) <= n.d) continue;  // the goal is not beyond the neighbour
    Vec3 side = Vec3::UnitZ().cross(n.h.a);
    if (side.norm() < 0.1) side = Vec3::UnitX().cross(n.h.a);  // one above the other
    // And apart in height, the lower id down: with three or more meeting at once, turning right
    // alone can circle into a deadlock (each blocked by the next); the heights break the tie.
    side = side.normalized() + Vec3(0, 0, self < n.id ? -0.5 : 0.5);
    u += side.normalized() * deficit;
  }
  if (speed > 0.0) u = clamp_norm(u, speed);

  std::vector<Halfspace> all;
  all.reserve(near.size());
  for (const Near& n : near) all.push_back(n.h);
  if (worst_violation(all, u) <= 1e-12) {
    out.v_W = u;
    return out;
  }
  // The QP keeps at most kMaxConstraints at a time: those that press hardest on u (the largest
  // b - a.u). A constraint left out that the answer breaks is swapped in for the kept one with the
  // most slack, and the QP solved again, until the answer meets them all.
  std::sort(all.begin(), all.end(), [&u](const Halfspace& a, const Halfspace& b) {
    return a.b - a.a.dot(u) > b.b - b.a.dot(u);
  });
  std::vector<Halfspace> kept(
      all.begin(), all.begin() + static_cast<long>(std::min(all.size(), kMaxConstraints)));
  std::vector<Halfspace> rest(
      kept.size() < all.size() ? all.begin() + static_cast<long>(kept.size()) : all.end(),
      all.end());
  for (int round = 0;; ++round) {
    solve_qp(kept, u, out);
    if (rest.empty() || round == 8) break;
    auto worst =
        std::max_element(rest.begin(), rest.end(), [&out](const Halfspace& a, const Halfspace& b) {
          return a.b - a.a.dot(out.v_W) < b.b - b.a.dot(out.v_W);
        });
    if (worst->b - worst->a.dot(out.v_W) <= 1e-9) break;
    auto slack =
        std::min_element(kept.begin(), kept.end(), [&out](const Halfspace& a, const Halfspace& b) {
          return a.b - a.a.dot(out.v_W) < b.b - b.a.dot(out.v_W);
        });
    std::swap(*worst, *slack);
  }
  if (worst_violation(all, out.v_W) > 1e-9) out.feasible = false;
  return out;
}

TrackingReference ReferenceGenerator::step(const Vec3& goal_W, double dt, AgentId self,
                                           const Vec3& self_p_W,
                                           const std::vector<Obstacle>& others,
                                           const AvoidanceConfig& avoid) {
  const double h = std::max(dt, 1e-9);
  const Vec3 v_des = clamp_norm(1.5 * (goal_W - p_W_), speed_);
  Vec3 a = clamp_norm((v_des - v_W_) / h, accel_);
  if (avoid.enabled) {
    const Vec3 v_cmd = v_W_ + a * dt;
    const SafeVelocity s = safe_velocity(self, self_p_W, v_cmd, goal_W, others, avoid);
    // Meeting a constraint may take harder braking than the comfortable limit, up to brake_mps2.
    a = clamp_norm((s.v_W - v_W_) / h, std::max(accel_, avoid.brake_mps2));
  }
  v_W_ += a * dt;
  p_W_ += v_W_ * dt;
  TrackingReference ref;
  ref.p_W = p_W_;
  ref.v_W = v_W_;
  ref.a_W = a;
  return ref;
}

}  // namespace qswarm
