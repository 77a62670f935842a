#include "agent/options.hpp"

#include <CLI/CLI.hpp>

#include "common/app/cli_checks.hpp"

namespace qswarm {

void add_agent_options(CLI::App& app, AgentFlags& f) {
  add_process_options(app, f.process);
  app.add_option("--id", f.id,
                 "this agent's id (listed in the scenario), or \"auto\": claim a free one over DDS "
                 "(replicas started alike, as by compose)")
      ->envname("QSWARM_AGENT_ID")
      ->required()
      ->check([](const std::string& v) -> std::string {
        if (v == "auto") return {};
        if (v.empty() || v.size() > 10 || v.find_first_not_of("0123456789") != std::string::npos ||
            std::stoull(v) == 0 || std::stoull(v) > 4294967295ULL)
          return "expected an agent id (1..4294967295) or \"auto\", got \"" + v + "\"";
        return {};
      });
  app.add_flag("--claim", f.claim,
               "announce the id on the DDS claim topic and refuse one another replica holds "
               "(implied by --id auto)");
  app.add_option("--claim-timeout", f.claim_timeout_s,
                 "--id auto: wall seconds to wait for every replica (default: the run plan's)")
      ->check(finite_range(1.0, 3600.0));
  app.add_option("--run-dir", f.run_dir, "directory for this agent's log")
      ->check(CLI::ExistingDirectory);
  app.add_option("--start-timeout", f.loop.start_timeout_s,
                 "wall seconds to wait for all peers (default: the run plan's)")
      ->check(finite_range(0.0, 3600.0));
  app.add_option("--max-wall", f.loop.max_wall_s, "stop after this many wall seconds running")
      ->check(finite_range(0.0, 1e6));
  app.add_option("--join-at", f.loop.join_at_s, "join late: start when the swarm's clock is here")
      ->check(finite_range(0.0, 1e7));
  app.add_flag("--restart", f.loop.restarted, "a restart: recover the flows this agent owned");
  app.add_flag("--wait-supervisor", f.loop.wait_supervisor, "start once a supervisor matched");
  app.add_flag("--ignore-sigterm", f.ignore_sigterm, "(tests) ignore SIGTERM")->group("");
}

}  // namespace qswarm
