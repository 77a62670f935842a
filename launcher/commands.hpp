#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>

namespace CLI {
class App;
}

namespace qswarm {

// The `swarm` command's subcommands, each in a file of its own with its flags. Each add_*
// declares its subcommand on `app` and returns what runs it once the command line is parsed: its
// exit code, or nothing when another subcommand was chosen.
using Command = std::function<std::optional<int>()>;
Command add_run_command(CLI::App& app);         // run_command.cpp: `swarm run`
Command add_inspect_command(CLI::App& app);     // inspect_command.cpp: `swarm inspect`
Command add_keys_command(CLI::App& app);        // keys_command.cpp: `swarm keys`
Command add_export_command(CLI::App& app);      // export_command.cpp: `swarm export`
Command add_view_command(CLI::App& app);        // view_command.cpp: `swarm view`
Command add_plot_command(CLI::App& app);        // python_commands.cpp: `swarm plot`
Command add_paper_command(CLI::App& app);       // ... `swarm paper`
Command add_resilience_command(CLI::App& app);  // ... `swarm resilience`
Command add_deploy_command(CLI::App& app);      // deploy_command.cpp: `swarm deploy k8s`
Command add_calibrate_command(CLI::App& app);   // calibrate_command.cpp: `swarm calibrate`
Command add_laws_command(CLI::App& app);        // law_commands.cpp: `swarm laws`
Command add_check_law_command(CLI::App& app);   // ... `swarm check-law`
Command add_plants_command(CLI::App& app);      // ... `swarm plants`

// Where this executable is, with swarm-agent, swarm-supervisor and the Python package beside it.
std::filesystem::path bin_dir();
// A default path of the repository's (`rel`, as in "scenarios/paper"): where the command runs,
// when it is run from the repository, else in the source tree the build came from, so that the
// defaults work from any directory.
std::string in_repository(const std::string& rel);

}  // namespace qswarm
