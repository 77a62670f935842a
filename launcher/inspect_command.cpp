// `swarm inspect SCENARIO [--json]`.
#include <CLI/CLI.hpp>

#include <memory>
#include <string>

#include "launcher/commands.hpp"
#include "launcher/inspect.hpp"

namespace qswarm {

Command add_inspect_command(CLI::App& app) {
  struct Options {
    std::string scenario;
    bool json = false;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "inspect", "initial graph, Laplacian, eigenvalues, predicted agreement, the run plan");
  cmd->add_option("scenario", o->scenario, "scenario file")->required()->check(CLI::ExistingFile);
  cmd->add_flag("--json", o->json, "machine-readable output");
  return [cmd, o]() -> std::optional<int> {
    if (!*cmd) return std::nullopt;
    return inspect_scenario(o->scenario, o->json);
  };
}

}  // namespace qswarm
