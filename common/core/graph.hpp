#pragma once

#include <algorithm>
#include <cstdint>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "common/core/math.hpp"
#include "common/core/topology.hpp"

namespace qswarm {

// Undirected weighted edge between vertex indices i < j (indices into a position list, not ids).
struct Edge {
  int i = 0;
  int j = 0;
  double weight = 1.0;
};

using Positions = std::vector<Vec3>;

// L = D - W for an undirected weighted graph on n vertices (paper, section 2.4).
Eigen::MatrixXd laplacian(int n, const std::vector<Edge>& edges);

struct Spectrum {
  Eigen::VectorXd eigenvalues;    // ascending
  double lambda2 = 0.0;           // algebraic connectivity (0 if disconnected)
  int components = 0;             // connected components of the graph
  std::vector<int> component_of;  // component index per vertex
};

// The eigenvalues (self-adjoint solver without eigenvectors: less than half the work at 256
// vertices, a quarter at 512) plus connected components from the edge structure.
Spectrum analyze(const Eigen::MatrixXd& L);
std::vector<int> connected_components(int n, const std::vector<Edge>& edges, int* count);

// The exact solution of the agreement protocol on a fixed graph: Q(t) = U exp(-Lambda t) U^T Q0.
Positions agreement_solution(const Eigen::MatrixXd& L, const Positions& q0, double t_s);

// The undirected graph the agents hold, by index into `ids`, from each agent's own links:
// links_of(i) yields (peer id, weight) pairs for agent ids[i]. An edge exists when either end holds
// it (peers not in `ids` are ignored); where both report one, the lower id's (the owner's) weight
// wins.
template <typename LinksOf>
std::vector<Edge> edges_from_links(const std::vector<AgentId>& ids, LinksOf&& links_of) {
  std::map<AgentId, int> index;
  for (int i = 0; i < static_cast<int>(ids.size()); ++i) index[ids[i]] = i;
  std::map<std::pair<int, int>, double> found;
  for (int i = 0; i < static_cast<int>(ids.size()); ++i) {
    for (const auto& [peer, w] : links_of(i)) {
      const auto j = index.find(peer);
      if (j == index.end()) continue;
      const auto key = std::minmax(i, j->second);
      if (ids[i] < peer || !found.count(key)) found[key] = w;
    }
  }
  std::vector<Edge> out;
  out.reserve(found.size());
  for (const auto& [key, w] : found) out.push_back({key.first, key.second, w});
  return out;
}

// What W-MSR with parameter F needs of an undirected graph on n vertices (LeBlanc et al., IEEE
// JSAC 2013): every vertex has at least 2F+1 neighbours (each can drop 2F values and keep one),
// and the graph is (F+1, F+1)-robust: for every two disjoint nonempty vertex sets S1, S2, one of
// them has all its members with F+1 neighbours outside it, or together they have F+1 such
// members. Robustness is decided exhaustively (3^n placements of the vertices), so only up to
// kMaxExactRobustness vertices; above, `robust` is unset.
struct ResilienceCheck {
  int f = 0;
  int min_degree = 0;
  bool degree_ok = false;      // min_degree >= 2F + 1
  std::optional<bool> robust;  // (F+1, F+1)-robust; unset: too large to decide here
  bool ok() const { return degree_ok && robust.value_or(true); }
};
constexpr int kMaxExactRobustness = 14;
ResilienceCheck check_resilience(int n, const std::vector<Edge>& edges, int f);
// (r, s)-robustness by exhaustion (n <= kMaxExactRobustness; std::invalid_argument above).
bool is_rs_robust(int n, const std::vector<Edge>& edges, int r, int s);

Vec3 average(const Positions& q);
// Largest distance of any point from the mean (the disagreement the supervisor reports).
double disagreement(const Positions& q);
// Largest distance of a point of q from the axis-aligned bounding box of `box` (0 when every point
// is inside it, or `box` is empty): where W-MSR promises its honest agents stay, per coordinate.
double outside_box_m(const Positions& q, const Positions& box);

}  // namespace qswarm
