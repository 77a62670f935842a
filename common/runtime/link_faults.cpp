#include "common/runtime/link_faults.hpp"

#include <algorithm>

namespace qswarm {
namespace {

bool matches(AgentId want, AgentId got) { return want == 0 || want == got; }
bool active(double start, double end, double t) { return t >= start && (end <= 0.0 || t < end); }
bool in_group(const std::vector<AgentId>& g, AgentId id) {
  return std::find(g.begin(), g.end(), id) != g.end();
}

}  // namespace

LinkFaults::LinkFaults(FaultPlan plan, AgentId self, std::uint64_t seed)
    : plan_(std::move(plan)), self_(self), seed_(seed) {}

LinkFaults::Link& LinkFaults::link(AgentId from) {
  auto it = links_.find(from);
  if (it == links_.end()) {
    it = links_
             .emplace(from, Link{std::mt19937_64(link_seed(seed_, from, self_)),
                                 std::vector<bool>(plan_.burst.size(), false)})
             .first;
  }
  return it->second;
}

bool LinkFaults::none() const {
  return plan_.cut.empty() && plan_.partition.empty() && plan_.loss.empty() &&
         plan_.burst.empty() && plan_.delay.empty();
}

bool LinkFaults::cut_now(AgentId from, double t) const {
  for (const FaultPlan::Cut& c : plan_.cut) {
    if (!active(c.start_s, c.end_s, t)) continue;
    if (c.a == from && c.b == self_) return true;
    if (!c.directed && c.b == from && c.a == self_) return true;
  }
  return false;
}

LinkFaults::Verdict LinkFaults::on_receive(AgentId from, double t) {
  Link& l = link(from);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  // Draw every random number for this message first, in a fixed order, so the stream of a link
  // does not depend on which fault happens to decide.
  std::vector<double>& draws = draws_;  // reused: no allocation per received sample
  draws.resize(plan_.loss.size() + 2 * plan_.burst.size() + plan_.delay.size());
  for (double& d : draws) d = u(l.rng);
  size_t k = 0;
  Verdict v;
  if (cut_now(from, t)) {
    ++counters_.cut;
    v.drop = true;
  }
  for (const FaultPlan::Partition& p : plan_.partition) {
    if (!v.drop && active(p.start_s, p.end_s, t) &&
        in_group(p.group, from) != in_group(p.group, self_)) {
      ++counters_.partition;
      v.drop = true;
    }
  }
  for (const FaultPlan::Loss& loss : plan_.loss) {
    const double d = draws[k++];
    if (!v.drop && matches(loss.from, from) && matches(loss.to, self_) &&
        active(loss.start_s, loss.end_s, t) && d < loss.probability) {
      ++counters_.loss;
      v.drop = true;
    }
  }
  for (size_t b = 0; b < plan_.burst.size(); ++b) {
    const FaultPlan::Burst& g = plan_.burst[b];
    const double d_state = draws[k++], d_loss = draws[k++];
    if (!matches(g.from, from) || !matches(g.to, self_)) continue;
    l.bad[b] = l.bad[b] ? d_state >= g.p_bad_to_good : d_state < g.p_good_to_bad;
    if (!v.drop && d_loss < (l.bad[b] ? g.loss_bad : g.loss_good)) {
      ++counters_.burst;
      v.drop = true;
    }
  }
  for (const FaultPlan::Delay& dl : plan_.delay) {
    const double d = draws[k++];
    if (matches(dl.from, from) && matches(dl.to, self_)) {
      v.delay_s += std::max(0.0, dl.mean_s + dl.jitter_s * (2.0 * d - 1.0));
    }
  }
  if (!v.drop && v.delay_s > 0.0) ++counters_.delayed;
  return v;
}

}  // namespace qswarm
