// swarm: launch a swarm of agent processes plus a supervisor (`swarm run`), analyse a scenario and
// its run plan without flying (`swarm inspect`), make a keystore (`swarm keys`), draw a run
// (`swarm plot`), rebuild its run.mcap (`swarm export`), replay it (`swarm view`), regenerate the
// paper's figures and report (`swarm paper`), or draw the laws under an insider's attacks (`swarm
// resilience`), or measure what this host sustains (`swarm calibrate`), list the agreement laws
// (`swarm laws`) or fly one through the promises it claims (`swarm check-law`). Each subcommand,
// with its flags, is a file of its own (launcher/commands.hpp).
#include <CLI/CLI.hpp>

#include <cstdlib>
#include <vector>

#include "launcher/commands.hpp"

int main(int argc, char** argv) {
  using namespace qswarm;
  // The compose swarm's variables are read by swarm-agent and swarm-supervisor as flag defaults;
  // `swarm run` passes everything its children need, so a shell that exported them for compose
  // must not change a local run.
  for (const char* v : {"QSWARM_AGENTS", "QSWARM_DISCOVERY_SERVER", "QSWARM_AGENT_ID",
                        "QSWARM_KEYSTORE", "QSWARM_PEER_HOSTS"})
    unsetenv(v);
  CLI::App app{"swarm: a quadcopter swarm that agrees over DDS"};
  app.require_subcommand(1);
  const std::vector<Command> commands = {
      add_run_command(app),       add_view_command(app),       add_inspect_command(app),
      add_keys_command(app),      add_plot_command(app),       add_export_command(app),
      add_paper_command(app),     add_resilience_command(app), add_deploy_command(app),
      add_calibrate_command(app), add_laws_command(app),       add_check_law_command(app),
      add_plants_command(app)};
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  for (const Command& c : commands)
    if (const std::optional<int> code = c()) return *code;
  return 2;
}
