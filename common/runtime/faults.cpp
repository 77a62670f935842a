#include "common/runtime/faults.hpp"

#include <algorithm>
#include <sstream>

namespace qswarm {
namespace {

bool matches(AgentId want, AgentId got) { return want == 0 || want == got; }
bool active(double start, double end, double t) { return t >= start && (end <= 0.0 || t < end); }
bool in_group(const std::vector<AgentId>& g, AgentId id) {
  return std::find(g.begin(), g.end(), id) != g.end();
}

}  // namespace

std::uint64_t link_seed(std::uint64_t seed, AgentId from, AgentId to) {
  // splitmix64 over (seed, from, to): independent, reproducible streams per directed link.
  std::uint64_t x = seed ^ (static_cast<std::uint64_t>(from) << 32) ^ to ^ 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

bool FaultPlan::empty() const {
  return loss.empty() && burst.empty() && cut.empty() && partition.empty() && delay.empty() &&
         kill.empty() && late_join.empty() && transport_drop_percent == 0;
}

double FaultPlan::last_fault_end_s() const {
  double t = 0.0;
  for (const Cut& c : cut) t = std::max(t, c.end_s > 0 ? c.end_s : c.start_s);
  for (const Partition& p : partition) t = std::max(t, p.end_s > 0 ? p.end_s : p.start_s);
  for (const Kill& k : kill) t = std::max(t, k.restart_at_s > k.at_s ? k.restart_at_s : k.at_s);
  for (const LateJoin& j : late_join) t = std::max(t, j.at_s);
  for (const Loss& l : loss) t = std::max(t, l.end_s);
  return t;
}

std::vector<FaultPlan::Event> FaultPlan::timeline() const {
  std::vector<Event> ev;
  for (const Cut& c : cut) {
    const std::string link = std::to_string(c.a) + (c.directed ? "->" : "-") + std::to_string(c.b);
    ev.push_back({c.start_s, "cut", c.a, "link " + link + " cut"});
    if (c.end_s > 0) ev.push_back({c.end_s, "cut_end", c.a, "link " + link + " restored"});
  }
  for (const Partition& p : partition) {
    std::ostringstream g;
    for (size_t i = 0; i < p.group.size(); ++i) g << (i ? " " : "") << p.group[i];
    ev.push_back({p.start_s, "partition", 0, "{" + g.str() + "} cut off from the rest"});
    if (p.end_s > 0) ev.push_back({p.end_s, "heal", 0, "partition {" + g.str() + "} healed"});
  }
  for (const Kill& k : kill) {
    ev.push_back({k.at_s, "kill", k.agent, "SIGKILL"});
    if (k.restart_at_s > k.at_s) ev.push_back({k.restart_at_s, "restart", k.agent, "restarted"});
  }
  for (const LateJoin& j : late_join) ev.push_back({j.at_s, "late_join", j.agent, "joins late"});
  for (const Loss& l : loss) {
    std::ostringstream d;
    d << "loss p=" << l.probability << " on " << (l.from ? std::to_string(l.from) : "*") << "->"
      << (l.to ? std::to_string(l.to) : "*");
    ev.push_back({l.start_s, "loss", 0, d.str()});
    if (l.end_s > 0) ev.push_back({l.end_s, "loss_end", 0, d.str()});
  }
  std::stable_sort(ev.begin(), ev.end(),
                   [](const Event& a, const Event& b) { return a.t_s < b.t_s; });
  return ev;
}

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

FaultyBus::FaultyBus(NeighborBus& inner, LinkFaults faults, AgentId self)
    : inner_(inner), faults_(std::move(faults)), self_(self) {}

void FaultyBus::set_time(double t) {
  std::lock_guard<std::mutex> lock(mu_);
  t_s_ = t;
}

void FaultyBus::deliver(const StateMessage& m) {
  std::lock_guard<std::mutex> lock(mu_);
  if (m.view.id == self_) return;
  const LinkFaults::Verdict v = faults_.on_receive(m.view.id, t_s_);
  if (v.drop) return;
  held_.emplace(t_s_ + v.delay_s, m);
  release_due_locked();
}

void FaultyBus::release_due_locked() {
  while (!held_.empty() && held_.begin()->first <= t_s_) {
    const StateMessage& m = held_.begin()->second;
    auto it = latest_.find(m.view.id);
    // Jitter can reorder: keep the newest.
    if (it == latest_.end() || is_newer(m, it->second)) {
      latest_[m.view.id] = m;
    }
    held_.erase(held_.begin());
  }
}

std::vector<StateMessage> FaultyBus::latest(AgentId self) {
  std::lock_guard<std::mutex> lock(mu_);
  release_due_locked();
  std::vector<StateMessage> out;
  for (const auto& [id, m] : latest_)
    if (id != self) out.push_back(m);
  return out;
}

FaultCounters FaultyBus::counters() const {
  std::lock_guard<std::mutex> lock(mu_);
  return faults_.counters();
}

}  // namespace qswarm
