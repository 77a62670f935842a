// The subcommands drawn by the Python package qswarm (matplotlib): `swarm plot`, `swarm paper`
// and `swarm resilience`.
#include <sys/wait.h>
#include <unistd.h>
#include <CLI/CLI.hpp>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "common/app/cli_checks.hpp"
#include "common/record/run_dir.hpp"
#include "common/scenario/scenario.hpp"
#include "common/sim/paper_maneuvers.hpp"
#include "common/transport/port_plan.hpp"
#include "launcher/commands.hpp"

namespace qswarm {

namespace fs = std::filesystem;

fs::path bin_dir() { return fs::read_symlink("/proc/self/exe").parent_path(); }

std::string in_repository(const std::string& rel) {
  std::error_code ec;
  if (fs::exists(rel, ec)) return rel;
  const fs::path source = fs::path(QSWARM_SOURCE_DIR) / rel;
  return fs::exists(source.parent_path(), ec) ? source.string() : rel;
}

namespace {

// Runs a module of the Python package qswarm (python/qswarm/), whose copy the build keeps beside
// this binary in python/, with Debian's interpreter first, where python3-matplotlib lives. Returns
// only when it cannot be started.
int exec_python(const std::string& command, const std::string& module,
                std::vector<std::string> module_args) {
  const fs::path package_root = bin_dir() / "python";
  const fs::path source = package_root / "qswarm" / (module + ".py");
  if (!fs::is_regular_file(source)) {
    std::cerr << command << ": " << source.string()
              << " is missing (the build copies python/qswarm/ there)\n";
    return 2;
  }
  const char* inherited = std::getenv("PYTHONPATH");
  const std::string path = package_root.string() +
                           (inherited && *inherited ? ":" + std::string(inherited) : std::string());
  setenv("PYTHONPATH", path.c_str(), 1);
  const std::string python = fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
  std::vector<std::string> args = {python, "-m", "qswarm." + module};
  args.insert(args.end(), module_args.begin(), module_args.end());
  std::vector<char*> argv;
  argv.reserve(args.size() + 1);
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  execvp(argv[0], argv.data());
  std::cerr << command << ": cannot run " << python << " (" << std::strerror(errno)
            << "); tools/setup.sh installs python3-matplotlib\n";
  return 2;
}

// `swarm resilience`: swarm-preview flies the scenario under every law and attack (the bare laws in
// lockstep); python -m qswarm.resilience draws them and prints the table.
int resilience(const std::string& scenario, const std::string& out, int liar) {
  std::vector<std::string> args = {"--swarm",    (bin_dir() / "swarm").string(),
                                   "--preview",  (bin_dir() / "swarm-preview").string(),
                                   "--scenario", scenario,
                                   "--out",      out};
  if (liar > 0) {
    args.emplace_back("--liar");
    args.push_back(std::to_string(liar));
  }
  return exec_python("swarm resilience", "resilience", args);
}

struct PaperOptions {
  std::string out = "docs/paper";
  std::string runs;  // where the runs go (default runs/TIMESTAMP-paper)
  std::string from;  // redraw from these runs, fly nothing
  std::string scenarios = "scenarios/paper";
  double time_scale = 4.0;
  int domain = -1;  // DDS domain for the runs (default: each scenario's)
};

// `swarm paper`: the section 4 maneuvers are simulated here (core primitives, in-process); the
// rendezvous scenarios are flown by `swarm run` and the figures and report are drawn by
// python -m qswarm.paper.
int paper(const PaperOptions& opt) {
  std::string runs = opt.from;
  if (runs.empty()) {
    const fs::path rendezvous = fs::path(opt.scenarios) / "rendezvous3.txtpb";
    RunConfig rc;
    try {
      rc = resolve_scenario(read_scenario_file(rendezvous.string()));
    } catch (const ScenarioError& e) {
      std::cerr << "swarm paper: " << e.what() << "\n";
      return 2;
    }
    try {
      runs = RunDir::claim(opt.runs, "paper", run_timestamp(), "runs", "--runs").str();
      fs::create_directories(fs::path(runs) / "maneuvers");
      write_paper_maneuvers(rc, (fs::path(runs) / "maneuvers").string());
    } catch (const RunDirError& e) {
      std::cerr << "swarm paper: " << e.what() << "\n";
      return 2;
    } catch (const std::exception& e) {
      std::cerr << "swarm paper: " << e.what() << "\n";
      return 3;
    }
  }
  std::vector<std::string> args = {"--swarm",      (bin_dir() / "swarm").string(),
                                   "--preview",    (bin_dir() / "swarm-preview").string(),
                                   "--scenarios",  opt.scenarios,
                                   "--runs",       runs,
                                   "--out",        opt.out,
                                   "--time-scale", std::to_string(opt.time_scale)};
  if (opt.domain >= 0) {
    args.emplace_back("--domain");
    args.push_back(std::to_string(opt.domain));
  }
  if (opt.from.empty()) args.emplace_back("--fly");
  return exec_python("swarm paper", "paper", args);
}

}  // namespace

Command add_plot_command(CLI::App& app) {
  struct Options {
    std::string run_dir, out;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("plot", "PNG figures of a run directory (matplotlib)");
  cmd->add_option("run_dir", o->run_dir, "run directory written by swarm run")->required();
  cmd->add_option("--out", o->out, "figure directory (default RUN_DIR/plots)");
  return [cmd, o]() -> std::optional<int> {
    if (!*cmd) return std::nullopt;
    // The figures are drawn by python -m qswarm.plot (matplotlib).
    std::vector<std::string> args = {"--swarm", (bin_dir() / "swarm").string(), o->run_dir};
    if (!o->out.empty()) args.insert(args.end(), {"--out", o->out});
    return exec_python("swarm plot", "plot", args);
  };
}

Command add_paper_command(CLI::App& app) {
  auto o = std::make_shared<PaperOptions>();
  CLI::App* cmd = app.add_subcommand(
      "paper", "fly the paper's scenarios and write its figures and a report (docs/paper)");
  cmd->add_option("--out", o->out, "figure and report directory (default docs/paper)");
  CLI::Option* runs =
      cmd->add_option("--runs", o->runs, "directory for the runs (default runs/TIMESTAMP-paper)");
  CLI::Option* from =
      cmd->add_option("--from", o->from,
                      "redraw from the runs of an earlier `swarm paper`, fly nothing")
          ->check(CLI::ExistingDirectory)
          ->excludes(runs);
  cmd->add_option("--scenarios", o->scenarios, "the paper's scenarios (default scenarios/paper)")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--time-scale", o->time_scale, "simulated seconds per wall second (default 4)")
      ->check(finite_range(0.01, 100.0))
      ->excludes(from);
  cmd->add_option("--domain", o->domain, "DDS domain id for the runs")
      ->check(CLI::Range(0, static_cast<int>(PortPlan::kMaxDomain)))
      ->excludes(from);
  return [cmd, o]() -> std::optional<int> {
    if (!*cmd) return std::nullopt;
    if (cmd->count("--scenarios") == 0) o->scenarios = in_repository(o->scenarios);
    if (cmd->count("--out") == 0) o->out = in_repository(o->out);
    return paper(*o);
  };
}

Command add_resilience_command(CLI::App& app) {
  struct Options {
    std::string scenario = "scenarios/insider_seven.txtpb", out = "docs/resilience";
    int liar = 0;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "resilience", "the three laws under one lying insider's attacks: figure and table (docs)");
  cmd->add_option("scenario", o->scenario,
                  "scenario (default scenarios/insider_seven.txtpb: 7 agents, complete graph)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "figure directory (default docs/resilience)");
  cmd->add_option("--liar", o->liar, "the lying agent's id (default the highest)")
      ->check(CLI::Range(1, 1000000));
  return [cmd, o]() -> std::optional<int> {
    if (!*cmd) return std::nullopt;
    if (cmd->count("scenario") == 0) o->scenario = in_repository(o->scenario);
    if (cmd->count("--out") == 0) o->out = in_repository(o->out);
    return resilience(o->scenario, o->out, o->liar);
  };
}

}  // namespace qswarm
