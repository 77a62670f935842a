#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "common/runtime/agent_loop.hpp"
#include "common/transport/neighbor_bus.hpp"

namespace qswarm {

class TickReceive;

// What the whole process has used so far (every thread's, getrusage RUSAGE_SELF).
struct ProcessUsage {
  double cpu_s = 0.0;             // user + system time
  long voluntary_switches = 0;    // a thread blocked: a sleep, a wait, an empty socket
  long involuntary_switches = 0;  // a thread was preempted
  long max_rss_kb = 0;
  double epoch_s = 0.0;  // when it was taken: the system clock, seconds since the Unix epoch
};
ProcessUsage process_usage();

// The agent's last log line: where it ended and what its transport and pacing did.
std::string final_report(const AgentLoop& loop, const BusCounters& c);
// Machine-readable stats for bench/swarm_scale.sh: agent-ID.stats in the run directory, with the
// number of other participants its DDS participant knows at the end and how old its neighbours'
// samples were when they reached its transport (p50 and p99 in ms, left out without any; "inf"
// beyond 14.8 s; and how many were stamped after they arrived). Returns whether the file was
// written completely. `flight_start`: the usage when the agent started running, after discovery
// (none: it never ran); the stats then also hold what the flight alone used (flight_cpu_s,
// flight_voluntary_switches, flight_involuntary_switches, over the same wall_s), without the
// process's start-up and discovery, which a short run's cpu_s is dominated by at small sizes, and
// when it started (started_epoch_s: how far apart a swarm's agents started).
// With receive at the tick (`tick` set): its drains and the datagrams they read (tick_drains,
// tick_datagrams, tick_truncated).
bool write_stats(const std::filesystem::path& path, const AgentLoop& loop, const BusCounters& c,
                 int participants_known, double wall_now_s,
                 const std::optional<ProcessUsage>& flight_start,
                 const TickReceive* tick = nullptr);

}  // namespace qswarm
