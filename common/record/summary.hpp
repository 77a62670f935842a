#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "common/record/convergence.hpp"
#include "common/record/presence.hpp"
#include "common/scenario/run_config.hpp"
#include "common/transport/state_message.hpp"
#include "proto/records.pb.h"

namespace qswarm {

// Forged samples of one agent of one SuspectKind, as noticed during a run.
struct ForgeryNote {
  double first_t_s = 0.0;
  std::set<AgentId> noticed_by;  // 0: the supervisor
};

// What the recorder counted during a run, for the summary.
struct RunTally {
  std::uint32_t joins = 0, departures = 0, fault_events = 0;
  std::uint64_t foreign_samples = 0;      // samples of other runs on this domain, refused
  std::uint64_t implausible_samples = 0;  // stamped far ahead of the swarm's clock, refused
  std::uint64_t unrecorded = 0;           // arrived while the supervisor's inbox was full
  double min_separation_m = 1e300;        // over every sample (SeparationMonitor)
  double min_separation_t_s = 0.0;
  AgentId min_separation_a = 0, min_separation_b = 0;
  std::uint32_t separation_violations = 0;
  std::set<AgentId> held;        // RunConfig::held_agents(): slots too close to another's to reach
  std::vector<double> ages_ms;   // sample ages (receive - send wall time)
  std::vector<double> detect_s;  // planned kill -> departure seen
  // Fault counters per agent incarnation (an incarnation's counters only grow).
  std::map<std::pair<AgentId, std::int64_t>, FaultCounters> fault_counts;
  // Forgeries by agent and kind (one SuspectKind bit).
  std::map<std::pair<AgentId, std::uint8_t>, ForgeryNote> forgeries;
  // Agents whose samples came from two writers at once: the record cannot tell which of their
  // samples were real, so the run does not converge.
  std::vector<AgentId> impersonated() const;
  // Law W_MSR: its condition over the run (trimmed is summed from the agents' last samples).
  std::optional<records::ResilienceOverTime> resilience;
  // The hosts each agent flew on, in order (StateMessage::host).
  std::map<AgentId, std::vector<std::string>> hosts;
};

struct RunEnd {
  std::string reason;  // converged, duration, interrupted, ...
  double t_s = 0.0;    // simulated time at the end
  double wall_time_s = 0.0;
  double time_scale = 1.0;
};

// summary.json's content from what the recorder saw. Pure.
records::Summary build_summary(const RunConfig& rc, const Presence& presence,
                               const ConvergenceJudge& judge, const RunTally& tally,
                               const std::optional<records::GraphSnapshot>& first,
                               const std::optional<records::GraphSnapshot>& last,
                               const RunEnd& end);
// The summary for people (what swarm run prints at the end).
std::string summary_text(const records::Summary& s, const RunConfig& rc, const std::string& dir);

}  // namespace qswarm
