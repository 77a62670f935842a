#include "common/scenario/fault_plan.hpp"

#include <algorithm>
#include <fstream>
#include <sstream>

namespace qswarm {

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
  for (const Kill& k : kill) t = std::max(t, k.restarts() ? k.restart_at_s : k.at_s);
  for (const LateJoin& j : late_join) t = std::max(t, j.at_s);
  for (const Loss& l : loss) t = std::max(t, l.end_s);
  return t;
}

std::optional<double> FaultPlan::late_join_at(AgentId id) const {
  for (const LateJoin& j : late_join)
    if (j.agent == id) return j.at_s;
  return std::nullopt;
}

std::set<AgentId> FaultPlan::late_joiners() const {
  std::set<AgentId> out;
  for (const LateJoin& j : late_join) out.insert(j.agent);
  return out;
}

std::vector<double> FaultPlan::kills_of(AgentId id, double from_s) const {
  std::vector<double> out;
  for (const Kill& k : kill)
    if (k.agent == id && k.at_s >= from_s) out.push_back(k.at_s);
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<double> FaultPlan::restarts_of(AgentId id) const {
  std::vector<double> out;
  for (const Kill& k : kill)
    if (k.agent == id && k.restarts()) out.push_back(k.restart_at_s);
  std::sort(out.begin(), out.end());
  return out;
}

bool FaultPlan::due_alive(AgentId id, double t_s) const {
  if (const auto j = late_join_at(id); j && t_s < *j) return false;
  for (const Kill& k : kill) {
    if (k.agent != id || t_s < k.at_s) continue;
    if (!k.restarts() || t_s < k.restart_at_s) return false;
  }
  return true;
}

bool FaultPlan::due_back(AgentId id, double t_s) const {
  if (!due_alive(id, t_s)) return false;
  if (const auto j = late_join_at(id); j && *j <= t_s) return true;
  for (const Kill& k : kill)
    if (k.agent == id && k.restarts() && k.restart_at_s <= t_s) return true;
  return false;
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
    if (k.restarts()) ev.push_back({k.restart_at_s, "restart", k.agent, "restarted"});
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

}  // namespace qswarm
