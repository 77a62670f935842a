// swarm: launch a swarm of agent processes plus a supervisor (`swarm run`), or analyse a scenario's
// initial graph without flying (`swarm inspect`).
#include <sys/wait.h>
#include <unistd.h>
#include <CLI/CLI.hpp>

#include <atomic>
#include <chrono>
#include <csignal>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <thread>

#include "common/core/graph.hpp"
#include "common/runtime/fault_flags.hpp"
#include "common/runtime/scenario.hpp"
#include "tools/process_group.hpp"

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

struct InitialGraph {
  std::vector<Edge> edges;
  Eigen::MatrixXd L;
  Spectrum spectrum;
};

InitialGraph initial_graph(const RunConfig& rc) {
  InitialGraph g;
  const int n = static_cast<int>(rc.agents.size());
  for (int i = 0; i < n; ++i) {
    LinkTracker tracker(rc.agents[i].id, rc.law.topology);
    for (int j = i + 1; j < n; ++j) {
      const double d = (rc.agents[i].position_W - rc.agents[j].position_W).norm();
      if (tracker.update(rc.agents[j].id, d)) {
        g.edges.push_back({i, j, weight_for_distance(rc.law.weight, d)});
      }
    }
  }
  g.L = laplacian(n, g.edges);
  g.spectrum = analyze(g.L);
  return g;
}

int inspect(const std::string& path, bool json) {
  RunConfig rc;
  try {
    rc = load_scenario(path);
  } catch (const ScenarioError& e) {
    std::cerr << "swarm inspect: " << e.what() << "\n";
    return 2;
  }
  const InitialGraph g = initial_graph(rc);
  const Vec3 avg = rc.initial_average();
  const double tau = g.spectrum.lambda2 > 0 ? 1.0 / (rc.law.gain * g.spectrum.lambda2) : -1.0;
  const int n = static_cast<int>(rc.agents.size());
  std::ostringstream o;
  o.precision(10);
  if (json) {
    o << "{\n  \"scenario\": \"" << rc.name << "\",\n  \"agents\": [";
    for (int i = 0; i < n; ++i) {
      const Vec3& p = rc.agents[i].position_W;
      o << (i ? ", " : "") << "{\"id\": " << rc.agents[i].id << ", \"position\": [" << p.x() << ", "
        << p.y() << ", " << p.z() << "]}";
    }
    o << "],\n  \"edges\": [";
    for (size_t k = 0; k < g.edges.size(); ++k) {
      o << (k ? ", " : "") << "[" << rc.agents[g.edges[k].i].id << ", "
        << rc.agents[g.edges[k].j].id << ", " << g.edges[k].weight << "]";
    }
    o << "],\n  \"laplacian\": [";
    for (int i = 0; i < n; ++i) {
      o << (i ? ", " : "") << "[";
      for (int j = 0; j < n; ++j) o << (j ? ", " : "") << g.L(i, j);
      o << "]";
    }
    o << "],\n  \"eigenvalues\": [";
    for (int i = 0; i < n; ++i) o << (i ? ", " : "") << g.spectrum.eigenvalues[i];
    o << "],\n  \"lambda2\": " << g.spectrum.lambda2
      << ",\n  \"components\": " << g.spectrum.components
      << ",\n  \"connected\": " << (g.spectrum.components == 1 ? "true" : "false")
      << ",\n  \"agreement_point\": [" << avg.x() << ", " << avg.y() << ", " << avg.z()
      << "],\n  \"time_constant_s\": " << tau << "\n}\n";
  } else {
    o.precision(6);
    o << "scenario " << rc.name << ": " << n << " agents, " << to_string(rc.law.weight.policy)
      << " weights, " << to_string(rc.law.topology.policy) << " topology, "
      << to_string(rc.law.kind) << " law, gain " << rc.law.gain << "\n";
    o << "initial edges (" << g.edges.size() << "):";
    for (const Edge& e : g.edges)
      o << " " << rc.agents[e.i].id << "-" << rc.agents[e.j].id << " (w=" << e.weight << ")";
    o << "\nweighted Laplacian:\n";
    for (int i = 0; i < n && n <= 16; ++i) {
      for (int j = 0; j < n; ++j) {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%10.4f", g.L(i, j));
        o << buf;
      }
      o << "\n";
    }
    if (n > 16) o << "  (" << n << " x " << n << ", not printed)\n";
    o << "eigenvalues:";
    for (int i = 0; i < std::min(n, 16); ++i) o << " " << g.spectrum.eigenvalues[i];
    o << "\nlambda2 " << g.spectrum.lambda2 << ", components " << g.spectrum.components
      << (g.spectrum.components == 1 ? " (connected)"
                                     : " (NOT connected: proximity may join them later)")
      << "\npredicted agreement point (the initial average): (" << avg.x() << ", " << avg.y()
      << ", " << avg.z() << ")\n";
    if (tau > 0) o << "time constant 1/(k lambda2) = " << tau << " s (exact for fixed weights)\n";
  }
  std::cout << o.str();
  return 0;
}

std::string timestamp() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y%m%d-%H%M%S", std::localtime(&t));
  return buf;
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
  double loss = -1.0;
  std::vector<std::string> cuts, partitions, kills;
  std::string delay;
  int transport_loss = -1;
  int random_cuts = 0;
};

int run(const RunOptions& opt) {
  RunConfig rc;
  ScenarioOverrides o;
  o.agents = opt.agents;
  o.seed = opt.seed;
  o.duration_s = opt.duration;
  o.domain_id = opt.domain;
  try {
    if (opt.scenario.empty() && opt.agents < 0) {
      throw ScenarioError("give a SCENARIO file, or --agents N for seeded random agents");
    }
    if (opt.agents == 0) throw ScenarioError("--agents: expected a count of at least 1");
    o.law = opt.law;
    scenario::Scenario s =
        opt.scenario.empty() ? random_scenario() : read_scenario_file(opt.scenario);
    if (opt.loss >= 0) add_loss_shortcut(s, opt.loss);
    for (const auto& c : opt.cuts) add_cut_shortcut(s, c);
    for (const auto& p : opt.partitions) add_partition_shortcut(s, p);
    for (const auto& k : opt.kills) add_kill_shortcut(s, k);
    if (!opt.delay.empty()) add_delay_shortcut(s, opt.delay);
    if (opt.transport_loss >= 0) {
      s.mutable_faults()->set_transport_drop_percent(
          static_cast<std::uint32_t>(opt.transport_loss));
    }
    if (opt.random_cuts > 0) {
      const RunConfig first = resolve_scenario(s, o);  // agents, duration and seed for the draw
      add_random_cuts(s, opt.random_cuts, static_cast<int>(first.agents.size()), first.duration_s,
                      first.seed);
    }
    rc = resolve_scenario(s, o);
  } catch (const ScenarioError& e) {
    std::cerr << "swarm run: " << e.what() << "\n";
    return 2;
  }
  fs::path dir =
      opt.out.empty() ? fs::path("runs") / (timestamp() + "-" + rc.name) : fs::path(opt.out);
  std::error_code ec;
  if (fs::exists(dir / "summary.json")) {
    std::cerr << "swarm run: --out " << dir
              << ": expected a new directory, this one holds a run already\n";
    return 2;
  }
  fs::create_directories(dir, ec);
  if (ec) {
    std::cerr << "swarm run: --out " << dir << ": cannot create (" << ec.message() << ")\n";
    return 2;
  }
  dir = fs::absolute(dir);
  const std::string scen = (dir / "scenario.txtpb").string();
  std::ofstream(scen) << "# The scenario as run (defaults filled in, agents listed).\n"
                      << to_text(rc.resolved);
  const InitialGraph g = initial_graph(rc);
  if (!opt.quiet) {
    std::cout << "swarm run: " << rc.name << ", " << rc.agents.size() << " agents, domain "
              << rc.domain_id << ", time scale " << opt.time_scale << ", seed " << rc.seed << "\n"
              << "initial graph: " << g.edges.size() << " edges, lambda2 " << g.spectrum.lambda2
              << (g.spectrum.components > 1 ? " (not connected yet)" : "")
              << "\nrun directory: " << dir.string() << std::endl;
  }

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGHUP, on_signal);
  const std::string ts = std::to_string(opt.time_scale);
  const std::string bin = bin_dir().string();
  ProcessGroup procs;
  const auto agent_args = [&](AgentId id, double join_at, bool restart) {
    std::vector<std::string> args = {
        bin + "/swarm-agent", "--scenario", scen,           "--id", std::to_string(id),
        "--run-dir",          dir.string(), "--time-scale", ts};
    if (join_at >= 0) {
      args.push_back("--join-at");
      args.push_back(std::to_string(join_at));
    }
    if (restart) args.push_back("--restart");
    args.push_back("--wait-supervisor");
    for (unsigned ign : opt.ignore_sigterm)
      if (ign == id) args.push_back("--ignore-sigterm");
    return args;
  };
  const auto agent_log = [&](AgentId id, int life) {
    return (dir / ("agent-" + std::to_string(id) + (life ? "-restart" + std::to_string(life) : "") +
                   ".out"))
        .string();
  };
  // Planned restarts per agent, in order: a planned kill's process dies by SIGKILL and is replaced.
  std::map<AgentId, std::vector<double>> restarts;
  for (const auto& k : rc.faults.kill)
    if (k.restart_at_s > k.at_s) restarts[k.agent].push_back(k.restart_at_s);
  std::map<AgentId, int> lives;
  try {
    std::vector<std::string> sup = {bin + "/swarm-supervisor",
                                    "--scenario",
                                    scen,
                                    "--run-dir",
                                    dir.string(),
                                    "--time-scale",
                                    ts};
    if (!opt.quiet) sup.push_back("--progress");
    procs.spawn("supervisor", 0, sup, opt.quiet ? (dir / "supervisor.out").string() : "");
    // The supervisor's reader first, so that it records the start.
    const auto ready_by = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (!fs::exists(dir / "supervisor.ready") && std::chrono::steady_clock::now() < ready_by &&
           procs.any_running() && procs.reap().empty()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    if (!procs.children().front().running || !fs::exists(dir / "supervisor.ready")) {
      // Without a recorder there is no run: start no agent.
      procs.reap();
      const auto sup_child = procs.children().front();
      throw std::runtime_error("the supervisor did not come up (" +
                               (sup_child.running ? std::string("no reader after 20 s")
                                                  : describe_status(sup_child.status)) +
                               ")" +
                               (opt.quiet ? "; see " + (dir / "supervisor.out").string() : ""));
    }
    for (const AgentSpec& a : rc.agents) {
      procs.spawn("agent", a.id, agent_args(a.id, -1.0, false), agent_log(a.id, 0));
    }
  } catch (const std::exception& e) {
    std::cerr << "swarm run: " << e.what() << "\n";
    procs.terminate_all(opt.grace_s);
    return 1;
  }
  {
    std::ofstream pids(dir / "processes.csv");
    pids << "role,id,pid\n";
    for (const auto& c : procs.children()) pids << c.role << ',' << c.id << ',' << c.pid << '\n';
  }

  // The supervisor is the first child; its state (running, exit status) lives in the group.
  const auto supervisor = [&procs] { return procs.children().front(); };
  std::string why;
  const auto wall0 = std::chrono::steady_clock::now();
  const double wall_limit = rc.duration_s / opt.time_scale + 120.0;
  while (true) {
    for (const auto& c : procs.reap()) {
      if (c.role == "agent") {
        std::cerr << "swarm run: agent " << c.id << " " << describe_status(c.status) << "\n";
        auto& planned = restarts[c.id];
        const int life = lives[c.id];
        if (WIFSIGNALED(c.status) && WTERMSIG(c.status) == SIGKILL &&
            life < static_cast<int>(planned.size())) {
          ++lives[c.id];
          std::cerr << "swarm run: restarting agent " << c.id << " (joins at t=" << planned[life]
                    << " s)\n";
          procs.spawn("agent", c.id, agent_args(c.id, planned[life], true),
                      agent_log(c.id, life + 1));
          std::ofstream(dir / "processes.csv", std::ios::app)
              << "agent," << c.id << ',' << procs.children().back().pid << '\n';
        } else if (opt.stop_on_agent_exit && why.empty()) {
          why = "agent " + std::to_string(c.id) + " exited";
        }
      }
    }
    if (!supervisor().running) break;
    if (g_signal) {
      why = "interrupted";
      break;
    }
    if (!why.empty()) break;
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count() >
        wall_limit) {
      why = "the supervisor did not finish in time";
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const int killed = procs.terminate_all(opt.grace_s);
  const int supervisor_status = supervisor().status;
  if (!opt.quiet || killed > 0) {
    std::cout << "swarm run: stopped " << procs.children().size() << " processes"
              << (killed ? " (" + std::to_string(killed) + " needed SIGKILL)" : std::string())
              << "\n";
  }
  if (!why.empty()) std::cerr << "swarm run: " << why << "\n";
  const bool converged = WIFEXITED(supervisor_status) && WEXITSTATUS(supervisor_status) == 0;
  std::cout << "swarm run: " << (converged ? "converged" : "not converged") << "; run record in "
            << dir.string() << std::endl;
  return converged ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
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
      ->check(CLI::PositiveNumber);
  run_cmd
      ->add_option("--time-scale", ro.time_scale, "simulated seconds per wall second (default 1)")
      ->check(CLI::Range(0.01, 100.0));
  run_cmd->add_option("--domain", ro.domain, "DDS domain id (overrides the scenario)")
      ->check(CLI::Range(0, 232));
  run_cmd->add_option("--grace", ro.grace_s, "seconds between SIGTERM and SIGKILL at teardown")
      ->check(CLI::NonNegativeNumber);
  run_cmd->add_flag("--quiet", ro.quiet, "no progress line");
  run_cmd->add_flag("--stop-on-agent-exit", ro.stop_on_agent_exit,
                    "end the run when any agent exits");
  run_cmd->add_option("--law", ro.law,
                      "update law: edge-flow or laplacian (overrides the scenario)");
  run_cmd->add_option("--loss", ro.loss, "fault: drop each received message with this probability")
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

  std::string inspect_path;
  bool json = false;
  CLI::App* inspect_cmd =
      app.add_subcommand("inspect", "initial graph, Laplacian, eigenvalues, predicted agreement");
  inspect_cmd->add_option("scenario", inspect_path, "scenario file")
      ->required()
      ->check(CLI::ExistingFile);
  inspect_cmd->add_flag("--json", json, "machine-readable output");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (*run_cmd) return run(ro);
  return inspect(inspect_path, json);
}
