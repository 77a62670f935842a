#pragma once

#include <filesystem>
#include <string>

#include "common/runtime/agent_loop.hpp"
#include "common/transport/neighbor_bus.hpp"

namespace qswarm {

// The agent's last log line: where it ended and what its transport and pacing did.
std::string final_report(const AgentLoop& loop, const BusCounters& c);
// Machine-readable stats for bench/swarm_scale.sh: agent-ID.stats in the run directory, with the
// number of other participants its DDS participant knows at the end and how old its neighbours'
// samples were when they reached its transport (p50 and p99 in ms, left out without any; "inf"
// beyond 14.8 s; and how many were stamped after they arrived). Returns whether the file was
// written completely.
bool write_stats(const std::filesystem::path& path, const AgentLoop& loop, const BusCounters& c,
                 int participants_known, double wall_now_s);

}  // namespace qswarm
