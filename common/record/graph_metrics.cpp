#include "common/record/graph_metrics.hpp"

#include <algorithm>

namespace qswarm {

records::GraphSnapshot measure_graph(double t_s, const std::vector<AgentId>& ids,
                                     const Positions& q, const Positions& p,
                                     const LinksOf& links_of, const Vec3& initial_average,
                                     const Positions& offsets, const std::vector<bool>& held) {
  records::GraphSnapshot g;
  g.set_t_s(t_s);
  g.set_agents(static_cast<std::uint32_t>(ids.size()));
  const std::vector<Edge> edges = edges_from_links(ids, links_of);
  for (const Edge& edge : edges) {
    records::GraphEdge* e = g.add_edges();
    e->set_a(ids[edge.i]);
    e->set_b(ids[edge.j]);
    e->set_weight(edge.weight);
  }
  const int n = static_cast<int>(ids.size());
  if (n == 0) return g;
  const Spectrum s = analyze(laplacian(n, edges));
  g.set_lambda2(s.lambda2);
  g.set_components(static_cast<std::uint32_t>(s.components));
  const Vec3 qbar = average(q);
  g.set_disagreement_m(disagreement(q));
  g.set_mean_drift_m((qbar - initial_average).norm());
  if (n > 1) {
    double min_sep = 1e300;
    for (int i = 0; i < n; ++i) {
      for (int j = i + 1; j < n; ++j) {
        const double d = (p[i] - p[j]).norm();
        if (d < min_sep) {
          min_sep = d;
          g.set_min_separation_a(ids[static_cast<std::size_t>(i)]);
          g.set_min_separation_b(ids[static_cast<std::size_t>(j)]);
        }
      }
    }
    g.set_min_separation_m(min_sep);
  }
  double spread = 0.0;
  for (int i = 0; i < n; ++i) {
    if (!held.empty() && held[static_cast<std::size_t>(i)]) continue;
    const Vec3 slot = offsets.empty() ? qbar : Vec3(qbar + offsets[static_cast<std::size_t>(i)]);
    spread = std::max(spread, (p[static_cast<std::size_t>(i)] - slot).norm());
  }
  g.set_spread_m(spread);
  return g;
}

}  // namespace qswarm
