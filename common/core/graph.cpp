#include "common/core/graph.hpp"

#include <bit>
#include <cstdint>
#include <numeric>
#include <stdexcept>

namespace qswarm {

Eigen::MatrixXd laplacian(int n, const std::vector<Edge>& edges) {
  Eigen::MatrixXd L = Eigen::MatrixXd::Zero(n, n);
  for (const Edge& e : edges) {
    if (e.i < 0 || e.j < 0 || e.i >= n || e.j >= n || e.i == e.j) {
      throw std::invalid_argument("laplacian: edge with a vertex out of range or a self-loop");
    }
    L(e.i, e.j) -= e.weight;
    L(e.j, e.i) -= e.weight;
    L(e.i, e.i) += e.weight;
    L(e.j, e.j) += e.weight;
  }
  return L;
}

std::vector<int> connected_components(int n, const std::vector<Edge>& edges, int* count) {
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  const auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const Edge& e : edges) {
    if (e.weight > 0.0) parent[find(e.i)] = find(e.j);
  }
  std::vector<int> label(n, -1), out(n);
  int next = 0;
  for (int v = 0; v < n; ++v) {
    const int r = find(v);
    if (label[r] < 0) label[r] = next++;
    out[v] = label[r];
  }
  if (count) *count = next;
  return out;
}

Spectrum analyze(const Eigen::MatrixXd& L) {
  const int n = static_cast<int>(L.rows());
  Spectrum s;
  if (n == 0) return s;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(L, Eigen::EigenvaluesOnly);
  s.eigenvalues = solver.eigenvalues();
  std::vector<Edge> edges;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      if (L(i, j) < 0.0) edges.push_back({i, j, -L(i, j)});
  s.component_of = connected_components(n, edges, &s.components);
  s.lambda2 = (n > 1 && s.components == 1) ? s.eigenvalues[1] : 0.0;
  return s;
}

Positions agreement_solution(const Eigen::MatrixXd& L, const Positions& q0, double t) {
  const int n = static_cast<int>(q0.size());
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(L);
  const Eigen::MatrixXd& U = solver.eigenvectors();
  const Eigen::VectorXd decay = (-solver.eigenvalues().array() * t).exp();
  Eigen::MatrixXd Q0(n, 3);
  for (int i = 0; i < n; ++i) Q0.row(i) = q0[i].transpose();
  const Eigen::MatrixXd Q = U * decay.asDiagonal() * U.transpose() * Q0;
  Positions out(n);
  for (int i = 0; i < n; ++i) out[i] = Q.row(i).transpose();
  return out;
}

namespace {
std::vector<std::uint32_t> adjacency_masks(int n, const std::vector<Edge>& edges) {
  std::vector<std::uint32_t> adj(static_cast<std::size_t>(n), 0u);
  for (const Edge& e : edges) {
    if (e.i < 0 || e.j < 0 || e.i >= n || e.j >= n || e.i == e.j)
      throw std::invalid_argument("robustness: edge with a vertex out of range or a self-loop");
    adj[e.i] |= 1u << e.j;
    adj[e.j] |= 1u << e.i;
  }
  return adj;
}

// Members of `set` with at least r neighbours outside it (X^r_S in LeBlanc et al.).
int reachable(const std::vector<std::uint32_t>& adj, std::uint32_t set, int r) {
  int count = 0;
  for (std::uint32_t m = set; m != 0; m &= m - 1) {
    const int v = std::countr_zero(m);
    count += std::popcount(adj[v] & ~set) >= r ? 1 : 0;
  }
  return count;
}
}  // namespace

bool is_rs_robust(int n, const std::vector<Edge>& edges, int r, int s) {
  if (n < 0 || n > kMaxExactRobustness)
    throw std::invalid_argument("robustness: decided exhaustively only up to " +
                                std::to_string(kMaxExactRobustness) + " vertices");
  const std::vector<std::uint32_t> adj = adjacency_masks(n, edges);
  const std::uint32_t all = n == 0 ? 0u : (1u << n) - 1u;
  for (std::uint32_t s1 = 1; s1 <= all; ++s1) {
    const int x1 = reachable(adj, s1, r);
    if (x1 == std::popcount(s1)) continue;  // S1 alone satisfies the condition for any S2
    const std::uint32_t rest = all & ~s1;
    // Every nonempty S2 inside the rest (the pair is unordered, but both orders are cheap).
    for (std::uint32_t s2 = rest; s2 != 0; s2 = (s2 - 1) & rest) {
      const int x2 = reachable(adj, s2, r);
      if (x2 != std::popcount(s2) && x1 + x2 < s) return false;
    }
  }
  return true;
}

ResilienceCheck check_resilience(int n, const std::vector<Edge>& edges, int f) {
  ResilienceCheck c;
  c.f = f;
  std::vector<int> degree(static_cast<std::size_t>(n), 0);
  for (const Edge& e : edges) {
    ++degree.at(e.i);
    ++degree.at(e.j);
  }
  c.min_degree = n == 0 ? 0 : *std::min_element(degree.begin(), degree.end());
  c.degree_ok = c.min_degree >= 2 * f + 1;
  if (n <= kMaxExactRobustness) c.robust = is_rs_robust(n, edges, f + 1, f + 1);
  return c;
}

Vec3 average(const Positions& q) {
  Vec3 sum = Vec3::Zero();
  for (const Vec3& x : q) sum += x;
  return q.empty() ? sum : Vec3(sum / static_cast<double>(q.size()));
}

double disagreement(const Positions& q) {
  const Vec3 mean = average(q);
  double worst = 0.0;
  for (const Vec3& x : q) worst = std::max(worst, (x - mean).norm());
  return worst;
}

double outside_box_m(const Positions& q, const Positions& box) {
  if (box.empty()) return 0.0;
  Vec3 lo = box.front(), hi = box.front();
  for (const Vec3& b : box) {
    lo = lo.cwiseMin(b);
    hi = hi.cwiseMax(b);
  }
  double worst = 0.0;
  for (const Vec3& x : q) {
    const Vec3 out = (lo - x).cwiseMax(x - hi).cwiseMax(Vec3::Zero());
    worst = std::max(worst, out.norm());
  }
  return worst;
}

}  // namespace qswarm
