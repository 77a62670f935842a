#pragma once

#include <string>

#include "common/runtime/agent_loop.hpp"
#include "common/transport/neighbor_bus.hpp"

namespace qswarm {

// The agent's last log line: where it ended and what its transport and pacing did.
std::string final_report(const AgentLoop& loop, const BusCounters& c);
// Machine-readable stats for bench/swarm_scale.sh: agent-ID.stats in the run directory.
void write_stats(const std::string& path, const AgentLoop& loop, const BusCounters& c,
                 double wall_now_s);

}  // namespace qswarm
