#pragma once

#include <algorithm>
#include <cstdint>
#include <map>
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
  Eigen::MatrixXd eigenvectors;   // orthonormal columns, same order
  double lambda2 = 0.0;           // algebraic connectivity (0 if disconnected)
  int components = 0;             // connected components of the graph
  std::vector<int> component_of;  // component index per vertex
};

// Eigen-decomposition (self-adjoint solver) plus connected components from the edge structure.
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

Vec3 average(const Positions& q);
// Largest distance of any point from the mean (the disagreement the supervisor reports).
double disagreement(const Positions& q);

}  // namespace qswarm
