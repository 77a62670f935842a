// swarm: launch a swarm of agent processes plus a supervisor (`swarm run`), analyse a scenario's
// initial graph without flying (`swarm inspect`), draw a run (`swarm plot`), rebuild its run.mcap
// (`swarm export`), regenerate the paper's figures and report (`swarm paper`), or draw the three
// laws under an insider's attacks (`swarm resilience`).
#include <sys/wait.h>
#include <unistd.h>
#include <CLI/CLI.hpp>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <random>

#include "common/app/cli_checks.hpp"
#include "common/mcap/file_check.hpp"
#include "common/record/mcap_export.hpp"
#include "common/record/run_dir.hpp"
#include "common/scenario/fault_flags.hpp"
#include "common/scenario/scenario.hpp"
#include "common/sim/paper_maneuvers.hpp"
#include "common/transport/port_plan.hpp"
#include "common/view/view_server.hpp"
#include "launcher/inspect.hpp"
#include "launcher/launcher.hpp"
#include "launcher/process_group.hpp"
#include "launcher/view_command.hpp"

namespace fs = std::filesystem;
using namespace qswarm;

namespace {

std::atomic<int> g_signal{0};
void on_signal(int sig) { g_signal = sig; }

fs::path bin_dir() { return fs::read_symlink("/proc/self/exe").parent_path(); }

// The scenario `swarm run --agents N` flies when no file is given.
scenario::Scenario random_scenario() {
  scenario::Scenario s;
  s.set_name("random");
  s.set_description("seeded random agents in a 30 m cube, sticky proximity 20 m, distance weights");
  s.mutable_topology()->set_policy(scenario::STICKY_PROXIMITY);
  s.mutable_topology()->set_threshold_m(20.0);
  s.mutable_weight()->set_policy(scenario::DISTANCE);
  s.mutable_random_agents()->set_box_m(30.0);
  return s;
}

struct RunOptions {
  std::string scenario;
  std::string out;
  int agents = -1;
  std::int64_t seed = -1;
  double duration = -1;
  double time_scale = 1.0;
  int domain = -1;
  double grace_s = 5.0;
  bool quiet = false;
  bool stop_on_agent_exit = false;
  std::vector<unsigned> ignore_sigterm;  // (tests) agents started with --ignore-sigterm
  // Fault shortcuts (added to the scenario's fault plan).
  std::string law;
  std::string secure;  // --secure KEYSTORE
  double loss = -1.0;
  std::vector<std::string> cuts, partitions, kills;
  std::string delay;
  int transport_loss = -1;
  int random_cuts = 0;
  int view_port = -1;  // --view [PORT]
  std::string view_listen = "127.0.0.1";
};

// The scenario file (or random agents) with the command line's overrides and fault shortcuts.
RunConfig resolve_run(const RunOptions& opt) {
  if (opt.scenario.empty() && opt.agents < 0) {
    throw ScenarioError("give a SCENARIO file, or --agents N for seeded random agents");
  }
  ScenarioOverrides o;
  o.agents = opt.agents;
  o.seed = opt.seed;
  o.duration_s = opt.duration;
  o.domain_id = opt.domain;
  o.law = opt.law;
  o.keystore = opt.secure;
  scenario::Scenario s =
      opt.scenario.empty() ? random_scenario() : read_scenario_file(opt.scenario);
  if (opt.loss >= 0) add_loss_shortcut(s, opt.loss);
  for (const auto& c : opt.cuts) add_cut_shortcut(s, c);
  for (const auto& p : opt.partitions) add_partition_shortcut(s, p);
  for (const auto& k : opt.kills) add_kill_shortcut(s, k);
  if (!opt.delay.empty()) add_delay_shortcut(s, opt.delay);
  if (opt.transport_loss >= 0) {
    s.mutable_faults()->set_transport_drop_percent(static_cast<std::uint32_t>(opt.transport_loss));
  }
  if (opt.random_cuts > 0) {
    const RunConfig first = resolve_scenario(s, o);  // agents, duration and seed for the draw
    add_random_cuts(s, opt.random_cuts, static_cast<int>(first.agents.size()),
                    first.judge.duration_s, first.seed);
  }
  RunConfig rc = resolve_scenario(s, o);
  // Checked here, before anything flies: an address not on this machine leaves every agent alone.
  if (const std::string problem = interface_problem(rc.transport.interface); !problem.empty())
    throw ScenarioError("scenario field 'transport.interface': " + problem);
  if (rc.agent.law.kind == LawKind::kWmsr) {
    const ResilienceCheck c = resilience_of(rc, initial_graph(rc));
    if (!c.ok() && rc.agent.law.topology.policy == TopologyPolicy::kFixed)
      throw ScenarioError("scenario field 'wmsr_f': " + describe(c, rc));
    if (!c.ok()) std::cerr << "swarm run: warning: " << describe(c, rc);
  }
  {
    // A fresh id for every run, even when the scenario is a previous run's scenario.txtpb (which
    // holds that run's id): two runs on one domain never hear each other.
    std::random_device rd;
    std::uint64_t id = 0;
    while (id == 0)
      id = (static_cast<std::uint64_t>(rd()) << 32) ^ rd() ^ static_cast<std::uint64_t>(::getpid());
    rc.transport.run_id = id;
    rc.resolved.mutable_transport()->set_run_id(id);
  }
  return rc;
}

// Runs a Python module of the package in a child process: its exit status (2 when it could not
// run). Defined below with exec_python.
int run_python(const std::string& command, const std::string& module,
               std::vector<std::string> module_args);

int run(const RunOptions& opt) {
  RunConfig rc;
  try {
    rc = resolve_run(opt);
  } catch (const ScenarioError& e) {
    std::cerr << "swarm run: " << e.what() << "\n";
    return 2;
  }
  // A keystore that is missing a file, expired, altered or not this scenario's stops the run here,
  // naming the file, before any process flies.
  if (!rc.transport.keystore.empty()) {
    const fs::path resolved =
        fs::temp_directory_path() / ("qswarm-keycheck-" + std::to_string(::getpid()) + ".txtpb");
    {
      std::ofstream f(resolved);
      f << to_text(rc.resolved);
    }
    const int checked = run_python("swarm run --secure", "keys",
                                   {"--swarm", (bin_dir() / "swarm").string(), resolved.string(),
                                    "--check", rc.transport.keystore});
    std::error_code ec;
    fs::remove(resolved, ec);
    if (checked != 0) return 2;
  }
  // Every process gets its own participant id, from a block whose ports are free on this host (so
  // hundreds of processes come up without Fast DDS shifting ports, and two runs on one domain do
  // not collide); a domain without room is the user's to change.
  // The supervisor, the agents and, with a Discovery Server, the server (the block's last id).
  const bool own_server = rc.transport.discovery == Discovery::kServer;
  const int participants = static_cast<int>(rc.agents.size()) + 1 + (own_server ? 1 : 0);
  std::optional<PortReservation> ports;
  std::optional<int> base;
  try {
    if (auto r = PortReservation::reserve(rc.transport.domain_id, participants,
                                          rc.transport.interface)) {
      ports.emplace(std::move(*r));
      base = ports->base();
    }
  } catch (const std::exception& e) {
    // Without the registry a run still takes ports that are free now; only a second run started
    // at the same moment on the same domain could then choose the same ones.
    std::cerr << "swarm run: warning: " << e.what() << "\n";
    base = free_participant_block(rc.transport.domain_id, participants, rc.transport.interface);
  }
  if (!base) {
    std::cerr << "swarm run: --domain " << rc.transport.domain_id << ": no room for "
              << participants
              << " more DDS participants on this host (other runs hold its ports); choose "
                 "another --domain (0 to "
              << PortPlan::kMaxDomain << ")\n";
    return 2;
  }
  if (opt.view_port >= 0) {
    // Said now, before anything is flown (port 0: the address alone); the supervisor checks again
    // when it listens.
    if (const std::string why =
            probe_listen(opt.view_listen, static_cast<std::uint16_t>(opt.view_port));
        !why.empty()) {
      std::cerr << "swarm run: --view " << opt.view_port << " (--view-listen " << opt.view_listen
                << "): " << why << "\n";
      return 2;
    }
  }
  RunDir dir;
  try {
    dir = RunDir::claim(opt.out, rc.name, run_timestamp());
  } catch (const RunDirError& e) {
    std::cerr << "swarm run: " << e.what() << "\n";
    return 2;
  }
  LaunchSpec spec;
  spec.rc = rc;
  spec.dir = dir;
  spec.bin_dir = bin_dir().string();
  spec.time_scale = opt.time_scale;
  spec.grace_s = opt.grace_s;
  spec.progress = !opt.quiet;
  spec.stop_on_agent_exit = opt.stop_on_agent_exit;
  spec.ignore_sigterm = opt.ignore_sigterm;
  spec.participant_base = *base;
  if (own_server) {
    spec.discovery_id = *base + participants - 1;
    // Written by the server once its participant listens. Not its ports seen taken: the server
    // binds them briefly itself to check them first, and a probe of them from here could take
    // them in that instant.
    spec.discovery_ready = [ready = dir.discovery_ready()] { return fs::exists(ready); };
  }
  spec.view_port = opt.view_port;
  spec.view_listen = opt.view_listen;
  if (!dir.write_scenario(rc.resolved)) {
    std::cerr << "swarm run: cannot write " << dir.scenario().string() << " (disk full?)\n";
    return 3;
  }
  if (!opt.quiet) {
    const InitialGraph g = initial_graph(rc);
    std::cout << "swarm run: " << rc.name << ", " << rc.agents.size() << " agents, domain "
              << rc.transport.domain_id << ", time scale " << opt.time_scale << ", seed " << rc.seed
              << "\n"
              << "initial graph: " << g.edges.size() << " edges, lambda2 " << g.spectrum.lambda2
              << (g.spectrum.components > 1 ? " (not connected yet)" : "")
              << "\nrun directory: " << dir.str() << std::endl;
  }

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGHUP, on_signal);
  ProcessGroup procs;
  SteadyClock clock;
  Launcher launcher(spec, procs, clock, [&] { return fs::exists(dir.supervisor_ready()); });
  try {
    launcher.start();
  } catch (const std::exception& e) {
    std::cerr << "swarm run: " << e.what() << "\n";
    launcher.stop();
    dir.write_fallback_summary(rc, e.what(), clock.now_s());
    return 1;
  }
  if (opt.view_port >= 0 && opt.quiet) {
    // Without the live line the supervisor's own announcement goes to supervisor.out.
    std::ifstream url(dir.path() / "view.url");
    std::string line;
    if (std::getline(url, line)) std::cout << "swarm run: live view on " << line << std::endl;
  }
  std::optional<std::string> why;
  while (!(why = launcher.poll(g_signal != 0))) clock.sleep_until(clock.now_s() + 0.02);
  const int killed = launcher.stop();
  if (!opt.quiet || killed > 0) {
    std::cout << "swarm run: stopped " << procs.children().size() << " processes"
              << (killed ? " (" + std::to_string(killed) + " needed SIGKILL)" : std::string())
              << "\n";
  }
  if (*why != Launcher::kFinished) std::cerr << "swarm run: " << *why << "\n";
  for (const std::string& p : launcher.problems()) std::cerr << "swarm run: " << p << "\n";
  const Launcher::Outcome outcome = launcher.conclude(clock.now_s());
  for (const std::string& line : outcome.lines)
    (outcome.exit_code == 0 ? std::cout : std::cerr) << "swarm run: " << line << std::endl;
  return outcome.exit_code;
}

// Runs a module of the Python package qswarm (python/qswarm/), whose copy the build keeps beside
// this binary in python/, with Debian's interpreter first, where python3-matplotlib lives. Returns
// only when it cannot be started.
int exec_python(const std::string& command, const std::string& module,
                std::vector<std::string> module_args);

// The same in a child process: its exit status (2 when it could not run or was killed).
int run_python(const std::string& command, const std::string& module,
               std::vector<std::string> module_args) {
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid < 0) {
    std::cerr << command << ": cannot fork (" << std::strerror(errno) << ")\n";
    return 2;
  }
  if (pid == 0) _exit(exec_python(command, module, std::move(module_args)));
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 2;
}

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

// `swarm plot`: the figures are drawn by python -m qswarm.plot (matplotlib).
int plot(const std::string& run_dir, const std::string& out) {
  std::vector<std::string> args = {"--swarm", (bin_dir() / "swarm").string(), run_dir};
  if (!out.empty()) {
    args.push_back("--out");
    args.push_back(out);
  }
  return exec_python("swarm plot", "plot", args);
}

// `swarm export --mcap RUN_DIR [--out FILE]`: run.mcap rebuilt from records.pb, for runs recorded
// before run.mcap existed and for a run.mcap cut short (a supervisor killed mid-run). 0 written; 2
// bad input (not a run directory, --out in no directory, a records.pb cut mid-record: its whole
// records are exported and the message says where it was cut); 3 the file could not be written.
int export_run(const std::string& run_dir, const std::string& out_flag) {
  const RunDir dir(run_dir);
  const fs::path out = out_flag.empty() ? dir.mcap() : fs::path(out_flag);
  const fs::path parent = fs::absolute(out).parent_path();
  if (!out_flag.empty() && !fs::is_directory(parent)) {
    std::cerr << "swarm export: --out " << out_flag << ": " << parent.string()
              << " is not a directory\n";
    return 2;
  }
  const bool replacing = out == dir.mcap() && fs::exists(out);
  const mcap::FileCheck before = replacing ? mcap::check_file(out) : mcap::FileCheck{};
  ExportResult r;
  try {
    r = export_mcap(dir, out);
  } catch (const ExportError& e) {
    std::cerr << "swarm export: " << e.what() << "\n";
    return 2;
  }
  if (!r.write_error.empty()) {
    std::cerr << "swarm export: could not write " << r.write_error << "\n";
    return 3;
  }
  if (replacing && !before.complete)
    std::cout << "swarm export: " << out.string() << " was incomplete (" << before.problem
              << "); rebuilt from " << dir.records().filename().string() << "\n";
  const auto n = [&](Stream s) { return r.messages[static_cast<std::size_t>(s)]; };
  std::cout << "swarm export: " << r.records << " records -> " << out.string() << " ("
            << n(Stream::kAgentSamples) << " samples, " << n(Stream::kGraph) << " graph snapshots, "
            << n(Stream::kEvents) << " events, " << n(Stream::kScene) << " scenes)\n";
  if (!r.partial.empty()) {
    std::cerr << "swarm export: " << r.partial << ": exported those, not the rest\n";
    return 2;
  }
  return 0;
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

int main(int argc, char** argv) {
  // The compose swarm's variables are read by swarm-agent and swarm-supervisor as flag defaults;
  // `swarm run` passes everything its children need, so a shell that exported them for compose
  // must not change a local run.
  for (const char* v : {"QSWARM_AGENTS", "QSWARM_DISCOVERY_SERVER", "QSWARM_AGENT_ID",
                        "QSWARM_KEYSTORE", "QSWARM_PEER_HOSTS"})
    unsetenv(v);
  CLI::App app{"swarm: a quadcopter swarm that agrees over DDS"};
  app.require_subcommand(1);
  RunOptions ro;
  CLI::App* run_cmd =
      app.add_subcommand("run", "launch the supervisor and one agent process per agent");
  run_cmd->add_option("scenario", ro.scenario, "scenario file (Protobuf text format)")
      ->check(CLI::ExistingFile);
  run_cmd->add_option("--out", ro.out, "run directory to create (default runs/TIMESTAMP-NAME)");
  run_cmd->add_option("--agents", ro.agents, "fly N agents from seeded random positions")
      ->check(CLI::Range(1, 512));
  run_cmd->add_option("--seed", ro.seed, "seed (overrides the scenario)")
      ->check(CLI::Range(std::int64_t{0}, std::int64_t{4294967295}));
  run_cmd->add_option("--duration", ro.duration, "simulated seconds before giving up")
      ->check(finite_range(1e-3, 1e7));
  run_cmd
      ->add_option("--time-scale", ro.time_scale, "simulated seconds per wall second (default 1)")
      ->check(finite_range(0.01, 100.0));
  run_cmd->add_option("--domain", ro.domain, "DDS domain id (overrides the scenario)")
      ->check(CLI::Range(0, static_cast<int>(PortPlan::kMaxDomain)));
  run_cmd->add_option("--grace", ro.grace_s, "seconds between SIGTERM and SIGKILL at teardown")
      ->check(finite_range(0.0, 600.0));
  run_cmd->add_flag("--quiet", ro.quiet, "no progress line");
  run_cmd
      ->add_option("--view", ro.view_port,
                   "serve the live view on http://127.0.0.1:PORT/ (default 8765; 0: any free "
                   "port; give it after SCENARIO)")
      ->expected(0, 1)
      ->default_str("8765")
      ->check(CLI::Range(0, 65535));
  run_cmd->add_option("--view-listen", ro.view_listen,
                      "address the live view listens on (default 127.0.0.1: this host only)");
  run_cmd->add_flag("--stop-on-agent-exit", ro.stop_on_agent_exit,
                    "end the run when any agent exits");
  run_cmd->add_option("--secure", ro.secure,
                      "DDS-Security with this keystore (swarm keys SCENARIO --out DIR writes one)");
  run_cmd->add_option("--law", ro.law,
                      "update law: edge-flow, laplacian or w-msr (overrides the scenario)");
  run_cmd->add_option("--loss", ro.loss, "fault: drop each received message with this probability")
      ->check(finite_range(0.0, 1.0))
      ->allow_extra_args(false)
      ->group("Faults");
  run_cmd
      ->add_option("--cut", ro.cuts,
                   "fault: cut link A-B over a window, e.g. 1-2@5:15 (repeatable)")
      ->allow_extra_args(false)
      ->group("Faults");
  run_cmd
      ->add_option("--partition", ro.partitions,
                   "fault: cut group off from the rest, e.g. 1,2,3@5:15")
      ->allow_extra_args(false)
      ->group("Faults");
  run_cmd
      ->add_option("--delay", ro.delay,
                   "fault: delay every message MEAN[:JITTER] seconds, e.g. 0.05:0.02")
      ->allow_extra_args(false)
      ->group("Faults");
  run_cmd
      ->add_option("--kill", ro.kills, "fault: SIGKILL agent ID at AT, restart at RESTART: 3@10:20")
      ->allow_extra_args(false)
      ->group("Faults");
  run_cmd
      ->add_option(
          "--transport-loss", ro.transport_loss,
          "fault below the application: Fast DDS test transport drops this % of data messages")
      ->check(CLI::Range(0, 100))
      ->allow_extra_args(false)
      ->group("Faults");
  run_cmd
      ->add_option("--random-cuts", ro.random_cuts,
                   "fault: N seeded random link cuts of 1-5 s, in the first 75% of the run")
      ->check(CLI::Range(0, 10000))
      ->allow_extra_args(false)
      ->group("Faults");
  run_cmd
      ->add_option("--test-ignore-sigterm", ro.ignore_sigterm, "(tests) agents that ignore SIGTERM")
      ->group("");

  ViewCommandOptions vo;
  CLI::App* view_cmd = app.add_subcommand(
      "view", "replay a recorded run in the live view (browser page, Foxglove WebSocket)");
  view_cmd->add_option("run_dir", vo.run_dir, "run directory written by swarm run")->required();
  view_cmd->add_option("--speed", vo.speed, "simulated seconds per wall second (default 1)");
  view_cmd->add_option("--port", vo.port, "port (default 8765; 0: any free port)")
      ->check(CLI::Range(0, 65535));
  view_cmd->add_option("--listen", vo.listen, "address (default 127.0.0.1: this host only)");

  std::string inspect_path;
  bool json = false;
  CLI::App* inspect_cmd =
      app.add_subcommand("inspect", "initial graph, Laplacian, eigenvalues, predicted agreement");
  inspect_cmd->add_option("scenario", inspect_path, "scenario file")
      ->required()
      ->check(CLI::ExistingFile);
  inspect_cmd->add_flag("--json", json, "machine-readable output");

  std::string keys_scenario, keys_out;
  int keys_days = 365;
  CLI::App* keys_cmd = app.add_subcommand(
      "keys", "a DDS-Security keystore for a scenario's agents and supervisor (openssl)");
  keys_cmd->add_option("scenario", keys_scenario, "scenario file")->required();
  keys_cmd->add_option("--out", keys_out, "new keystore directory")->required();
  keys_cmd->add_option("--days", keys_days, "validity in days (default 365)")
      ->check(CLI::Range(1, 36500));
  bool keys_compose = false;
  keys_cmd->add_flag("--compose", keys_compose,
                     "one member identity for compose replicas (they claim their ids) instead of "
                     "one per agent");
  std::string plot_dir, plot_out;
  CLI::App* plot_cmd = app.add_subcommand("plot", "PNG figures of a run directory (matplotlib)");
  plot_cmd->add_option("run_dir", plot_dir, "run directory written by swarm run")->required();
  plot_cmd->add_option("--out", plot_out, "figure directory (default RUN_DIR/plots)");
  std::string export_dir, export_out;
  CLI::App* export_cmd = app.add_subcommand(
      "export", "rebuild a run's run.mcap (Foxglove, Lichtblick) from its records.pb");
  export_cmd->add_option("--mcap", export_dir, "the run directory whose records.pb to export")
      ->required();
  export_cmd->add_option("--out", export_out, "the MCAP file to write (default RUN_DIR/run.mcap)");
  PaperOptions po;
  CLI::App* paper_cmd = app.add_subcommand(
      "paper", "fly the paper's scenarios and write its figures and a report (docs/paper)");
  paper_cmd->add_option("--out", po.out, "figure and report directory (default docs/paper)");
  CLI::Option* paper_runs = paper_cmd->add_option(
      "--runs", po.runs, "directory for the runs (default runs/TIMESTAMP-paper)");
  CLI::Option* paper_from =
      paper_cmd
          ->add_option("--from", po.from,
                       "redraw from the runs of an earlier `swarm paper`, fly nothing")
          ->check(CLI::ExistingDirectory)
          ->excludes(paper_runs);
  paper_cmd
      ->add_option("--scenarios", po.scenarios, "the paper's scenarios (default scenarios/paper)")
      ->check(CLI::ExistingDirectory);
  paper_cmd
      ->add_option("--time-scale", po.time_scale, "simulated seconds per wall second (default 4)")
      ->check(finite_range(0.01, 100.0))
      ->excludes(paper_from);
  paper_cmd->add_option("--domain", po.domain, "DDS domain id for the runs")
      ->check(CLI::Range(0, static_cast<int>(PortPlan::kMaxDomain)))
      ->excludes(paper_from);
  std::string res_scenario = "scenarios/insider_seven.txtpb", res_out = "docs/resilience";
  int res_liar = 0;
  CLI::App* res_cmd = app.add_subcommand(
      "resilience", "the three laws under one lying insider's attacks: figure and table (docs)");
  res_cmd
      ->add_option("scenario", res_scenario,
                   "scenario (default scenarios/insider_seven.txtpb: 7 agents, complete graph)")
      ->check(CLI::ExistingFile);
  res_cmd->add_option("--out", res_out, "figure directory (default docs/resilience)");
  res_cmd->add_option("--liar", res_liar, "the lying agent's id (default the highest)")
      ->check(CLI::Range(1, 1000000));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (*run_cmd) return run(ro);
  if (*plot_cmd) return plot(plot_dir, plot_out);
  if (*keys_cmd) {
    std::vector<std::string> args = {
        "--swarm", (bin_dir() / "swarm").string(), keys_scenario, "--out", keys_out,
        "--days",  std::to_string(keys_days)};
    if (keys_compose) args.push_back("--compose");
    return exec_python("swarm keys", "keys", args);
  }
  if (*paper_cmd) return paper(po);
  if (*export_cmd) return export_run(export_dir, export_out);
  if (*res_cmd) return resilience(res_scenario, res_out, res_liar);
  if (*view_cmd) return view_command(vo);
  return inspect_scenario(inspect_path, json);
}
