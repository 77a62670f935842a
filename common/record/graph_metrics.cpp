#include "common/record/graph_metrics.hpp"

#include <algorithm>

namespace qswarm {
namespace {

// Largest distance of a kept agent's position from its slot (the kept states' mean + its offset).
double spread_of(const std::vector<bool>& keep, const Positions& q, const Positions& p,
                 const Positions& offsets, const std::vector<bool>& held) {
  Vec3 qbar = Vec3::Zero();
  int n = 0;
  for (std::size_t i = 0; i < q.size(); ++i)
    if (keep[i]) {
      qbar += q[i];
      ++n;
    }
  if (n == 0) return 0.0;
  qbar /= n;
  double spread = 0.0;
  for (std::size_t i = 0; i < q.size(); ++i) {
    if (!keep[i] || (!held.empty() && held[i])) continue;
    const Vec3 slot = offsets.empty() ? qbar : Vec3(qbar + offsets[i]);
    spread = std::max(spread, (p[i] - slot).norm());
  }
  return spread;
}

Positions kept(const Positions& v, const std::vector<bool>& keep) {
  Positions out;
  for (std::size_t i = 0; i < v.size(); ++i)
    if (keep[i]) out.push_back(v[i]);
  return out;
}

// W-MSR: take out the state farthest from the others' mean, one at a time, at most F, while the
// rest disagree by the tolerance or more.
void measure_trimmed(records::GraphSnapshot& g, const std::vector<AgentId>& ids, const Positions& q,
                     const Positions& p, const Positions& offsets, const std::vector<bool>& held,
                     const WmsrMeasure& w) {
  std::vector<bool> keep(q.size(), true);
  for (int out = 0; out < w.f && out + 1 < static_cast<int>(q.size()); ++out) {
    const Positions rest = kept(q, keep);
    if (disagreement(rest) < w.tolerance_m) break;
    const Vec3 mean = average(rest);
    std::size_t far = 0;
    double far_m = -1.0;
    for (std::size_t i = 0; i < q.size(); ++i)
      if (keep[i] && (q[i] - mean).norm() > far_m) {
        far_m = (q[i] - mean).norm();
        far = i;
      }
    keep[far] = false;
    g.add_trimmed_agents(ids[far]);
  }
  const Positions rest = kept(q, keep);
  g.set_trimmed_disagreement_m(disagreement(rest));
  g.set_trimmed_spread_m(spread_of(keep, q, p, offsets, held));
  if (w.q0.size() == q.size())
    g.set_outside_initial_box_m(outside_box_m({average(rest)}, kept(w.q0, keep)));
}

bool same_edges(const std::vector<Edge>& a, const std::vector<Edge>& b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(), [](const Edge& x, const Edge& y) {
    return x.i == y.i && x.j == y.j && x.weight == y.weight;
  });
}

}  // namespace

records::GraphSnapshot measure_graph(double t_s, const std::vector<AgentId>& ids,
                                     const Positions& q, const Positions& p,
                                     const LinksOf& links_of, const Vec3& initial_average,
                                     const Positions& offsets, const std::vector<bool>& held,
                                     const WmsrMeasure* wmsr, SpectrumMemo* memo) {
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
  // Only links to agents of the snapshot (running) count: one to a departed peer lapses with its
  // neighbour timeout.
  std::vector<AgentId> sorted = ids;
  std::sort(sorted.begin(), sorted.end());
  std::size_t min_degree = static_cast<std::size_t>(n);
  for (int i = 0; i < n; ++i) {
    std::size_t degree = 0;
    for (const auto& [peer, w] : links_of(i))
      degree += std::binary_search(sorted.begin(), sorted.end(), peer) ? 1 : 0;
    min_degree = std::min(min_degree, degree);
  }
  g.set_min_degree(static_cast<std::uint32_t>(min_degree));
  double lambda2 = 0.0;
  int components = 0;
  if (memo && memo->valid && memo->ids == ids && same_edges(memo->edges, edges)) {
    ++memo->reused;
    lambda2 = memo->lambda2;
    components = memo->components;
  } else {
    const Spectrum s = analyze(laplacian(n, edges));
    lambda2 = s.lambda2;
    components = s.components;
    if (memo) {
      memo->ids = ids;
      memo->edges = edges;
      memo->lambda2 = lambda2;
      memo->components = components;
      memo->valid = true;
      ++memo->computed;
    }
  }
  g.set_lambda2(lambda2);
  g.set_components(static_cast<std::uint32_t>(components));
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
  g.set_spread_m(spread_of(std::vector<bool>(q.size(), true), q, p, offsets, held));
  if (wmsr) measure_trimmed(g, ids, q, p, offsets, held, *wmsr);
  return g;
}

}  // namespace qswarm
