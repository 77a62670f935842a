#include "common/runtime/run_config.hpp"

#include <random>

namespace qswarm {

Vec3 RunConfig::initial_average() const {
  Vec3 sum = Vec3::Zero();
  for (const AgentSpec& a : agents) sum += a.position_W;
  return agents.empty() ? sum : Vec3(sum / static_cast<double>(agents.size()));
}

const AgentSpec* RunConfig::agent(AgentId id) const {
  for (const AgentSpec& a : agents)
    if (a.id == id) return &a;
  return nullptr;
}

std::set<AgentId> RunConfig::ids() const {
  std::set<AgentId> out;
  for (const AgentSpec& a : agents) out.insert(a.id);
  return out;
}

std::set<AgentId> RunConfig::start_peers(AgentId id) const {
  std::set<AgentId> peers;
  if (law.topology.policy == TopologyPolicy::kFixed) {
    peers = listed_peers(law.topology, id);
  } else {
    for (const AgentSpec& a : agents)
      if (a.id != id) peers.insert(a.id);
  }
  for (const AgentId late : faults.late_joiners()) peers.erase(late);
  return peers;
}

std::vector<AgentSpec> random_agent_specs(int n, std::uint64_t seed, double box_m) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, box_m);
  std::vector<AgentSpec> out;
  for (int i = 0; i < n; ++i) {
    const double x = u(rng), y = u(rng), z = u(rng);
    out.push_back({static_cast<AgentId>(i + 1), Vec3(x, y, z), 0.0});
  }
  return out;
}

}  // namespace qswarm
