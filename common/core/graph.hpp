#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Dense>

#include "common/core/math.hpp"

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

Vec3 average(const Positions& q);
// Largest distance of any point from the mean (the disagreement the supervisor reports).
double disagreement(const Positions& q);

}  // namespace qswarm
