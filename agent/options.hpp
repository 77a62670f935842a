#pragma once

#include <string>

#include "common/app/process_options.hpp"
#include "common/runtime/agent_loop.hpp"

namespace CLI {
class App;
}

namespace qswarm {

// swarm-agent's flags: the ones every process takes, and this agent's own.
struct AgentFlags {
  ProcessOptions process;
  AgentLoopOptions loop;
  std::string run_dir;            // for agent-ID.log and agent-ID.stats
  std::string id;                 // --id / QSWARM_AGENT_ID: a listed agent id, or "auto"
  bool claim = false;             // announce the id on the claim topic, refuse duplicates
  double claim_timeout_s = -1.0;  // --id auto: wait this long for every replica (-1: the plan's)
  bool ignore_sigterm = false;    // (tests) exercise the launcher's SIGKILL escalation
};
void add_agent_options(CLI::App& app, AgentFlags& f);

}  // namespace qswarm
