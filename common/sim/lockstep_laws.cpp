#include "common/sim/lockstep_laws.hpp"

#include <map>
#include <set>
#include <stdexcept>

namespace qswarm {
namespace {

std::vector<NeighborView> others(const std::map<AgentId, NeighborView>& views, AgentId self) {
  std::vector<NeighborView> out;
  out.reserve(views.size());
  for (const auto& [id, v] : views)
    if (id != self) out.push_back(v);
  return out;
}

}  // namespace

LockstepLaws::LockstepLaws(LockstepConfig cfg) : cfg_(std::move(cfg)) {
  if (!(cfg_.consensus_rate_hz > 0.0)) throw std::invalid_argument("consensus_rate_hz must be > 0");
  std::set<AgentId> ids;
  for (const SwarmAgentSpec& a : cfg_.agents) {
    if (!ids.insert(a.id).second) throw std::invalid_argument("duplicate agent id");
    laws_.push_back(make_law(a.id, a.q0, cfg_.law));
  }
  for (const auto& law : laws_) views_[law->id()] = law->message();
  if (cfg_.liar && !ids.count(cfg_.liar->id)) throw std::invalid_argument("the liar is no agent");
  // Links are found from the first messages before anyone moves, so every published total weight
  // is known at the first tick.
  for (auto& law : laws_) law->observe(others(views_, law->id()));
  for (const auto& law : laws_) views_[law->id()] = law->message();
}

void LockstepLaws::step() {
  std::vector<std::vector<NeighborView>> inbox;
  inbox.reserve(laws_.size());
  for (const auto& law : laws_) {
    inbox.push_back(others(views_, law->id()));
    if (!cfg_.liar) continue;
    for (NeighborView& v : inbox.back())
      if (v.id == cfg_.liar->id) v.q = cfg_.liar->claim(law->id(), v.q0, time_s_);
  }
  for (size_t i = 0; i < laws_.size(); ++i) laws_[i]->step(dt_s(), inbox[i]);
  time_s_ += dt_s();
  for (const auto& law : laws_) views_[law->id()] = law->message();
}

bool LockstepLaws::run_until_converged(double tol_m, double max_time_s) {
  while (time_s_ < max_time_s) {
    if (disagreement(states()) < tol_m) return true;
    step();
  }
  return disagreement(states()) < tol_m;
}

Positions LockstepLaws::states() const {
  Positions q;
  for (const auto& law : laws_) q.push_back(law->state());
  return q;
}

Positions LockstepLaws::honest_states() const {
  Positions q;
  for (int i = 0; i < size(); ++i)
    if (!is_liar(i)) q.push_back(laws_[i]->state());
  return q;
}

Positions LockstepLaws::honest_initial_states() const {
  Positions q;
  for (int i = 0; i < size(); ++i)
    if (!is_liar(i)) q.push_back(laws_[i]->initial_state());
  return q;
}

Positions LockstepLaws::initial_states() const {
  Positions q;
  for (const auto& law : laws_) q.push_back(law->initial_state());
  return q;
}

std::vector<Edge> LockstepLaws::edges() const {
  std::vector<AgentId> ids;
  for (const auto& law : laws_) ids.push_back(law->id());
  return edges_from_links(
      ids, [&](int i) -> const auto& { return laws_[i]->links(); });
}

std::vector<SwarmAgentSpec> LockstepLaws::random_agents(int n, std::uint64_t seed, double box_m) {
  // The scenario's generator (random_agents { count box_m } with `seed`), so a test's agents and a
  // scenario file's are the same points.
  std::vector<SwarmAgentSpec> out;
  for (const AgentSpec& a : random_agent_specs(n, seed, box_m, 0.0)) out.push_back({a.id, a.q0()});
  return out;
}

}  // namespace qswarm
