#pragma once

// Numbers from "Multi-agent Systems for Quadcopters" (Carney, Chyba, Gray, Shanbrom, Wilkens),
// section 2, with the paper's precision. Agent ids are 1..4 as in the paper; edges use 0-based
// indices.
#include <vector>

#include "common/core/graph.hpp"
#include "common/core/topology.hpp"

namespace qswarm::paper {

// 2.6.1 "Rendezvous Mission, Unweighted Network": q* = (10.25, 9.75, 29.25).
inline const Positions kUnweightedQ0 = {{4, 17, 24}, {18, 10, 32}, {15, 10, 26}, {4, 2, 35}};
inline const Vec3 kUnweightedAgreement{10.25, 9.75, 29.25};
// Scenario 1 (L_1): 1-2, 2-3, 2-4, 3-4. Scenario 2 (L_2): 1-3, 1-4, 2-3.
inline const std::vector<std::pair<AgentId, AgentId>> kGraph1 = {{1, 2}, {2, 3}, {2, 4}, {3, 4}};
inline const std::vector<std::pair<AgentId, AgentId>> kGraph2 = {{1, 3}, {1, 4}, {2, 3}};

// 2.7.1 "Rendezvous Mission, Weighted Network": q* = (9, 12.75, 30.25), graph 1, weights due to
// initial distance; spectrum {0, 13.060, 42.248, 62.558}.
inline const Positions kWeightedQ0 = {{2, 16, 29}, {14, 20, 31}, {10, 1, 25}, {10, 14, 36}};
inline const Vec3 kWeightedAgreement{9, 12.75, 30.25};

// 2.7.2 "Rendezvous Mission, Time-varying Weighted Network": q* = (15.25, 10.25, 31); initial graph
// as graph 2 (1-3, 1-4, 2-3) with distance weights, edges added by proximity.
inline const Positions kTimeVaryingQ0 = {{16, 5, 36}, {19, 19, 29}, {12, 16, 33}, {14, 1, 26}};
inline const Vec3 kTimeVaryingAgreement{15.25, 10.25, 31};

inline std::vector<Edge> to_index_edges(const std::vector<std::pair<AgentId, AgentId>>& ids,
                                        const Positions* q0_for_distance = nullptr) {
  std::vector<Edge> out;
  for (const auto& [a, b] : ids) {
    const int i = static_cast<int>(a) - 1, j = static_cast<int>(b) - 1;
    const double w = q0_for_distance ? ((*q0_for_distance)[i] - (*q0_for_distance)[j]).norm() : 1.0;
    out.push_back({i, j, w});
  }
  return out;
}

}  // namespace qswarm::paper
