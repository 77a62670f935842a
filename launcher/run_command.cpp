// `swarm run`: resolve the run, plan it, claim its directory and ports, and fly it (Launcher).
#include <unistd.h>
#include <CLI/CLI.hpp>

#include <csignal>
#include <filesystem>
#include <iostream>
#include <memory>
#include <random>

#include "common/app/cli_checks.hpp"
#include "common/core/law_registry.hpp"
#include "common/record/run_dir.hpp"
#include "common/runtime/run_load.hpp"
#include "common/scenario/fault_flags.hpp"
#include "common/scenario/scenario.hpp"
#include "common/security/keystore.hpp"
#include "common/transport/port_plan.hpp"
#include "common/view/view_server.hpp"
#include "launcher/commands.hpp"
#include "launcher/inspect.hpp"
#include "launcher/launcher.hpp"
#include "launcher/process_group.hpp"

namespace qswarm {

namespace fs = std::filesystem;

namespace {

std::atomic<int> g_signal{0};
void on_signal(int sig) { g_signal = sig; }

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
  std::vector<int> hung_servers;         // (tests) the run's servers that hang once they listen
  // Fault shortcuts (added to the scenario's fault plan).
  std::string law, plant;
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
  o.plant = opt.plant;
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
  if (honest_hull_f(rc.agent.law) >= 0) {
    const ResilienceCheck c = resilience_of(rc, initial_graph(rc));
    if (!c.ok() && rc.agent.law.topology.policy == TopologyPolicy::kFixed)
      throw ScenarioError("scenario field 'law_params[\"f\"]': " + describe(c, rc));
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
  // Planned again with the run's id (its partitions and multicast group) and time scale.
  Hosts hosts = rc.plan.hosts;
  hosts.time_scale = opt.time_scale;
  replan(rc, hosts);
  return rc;
}

int run(const RunOptions& opt) {
  RunConfig rc;
  try {
    rc = resolve_run(opt);
  } catch (const ScenarioError& e) {
    std::cerr << "swarm run: " << e.what() << "\n";
    return 2;
  }
  for (const int k : opt.hung_servers) {
    if (k < rc.plan.own_servers) continue;
    std::cerr << "swarm run: --test-hung-server " << k << ": the run starts " << rc.plan.own_servers
              << " Discovery Servers of its own (transport.discovery "
              << "SERVER: two, 0 and 1)\n";
    return 2;
  }
  // A keystore that is missing a file, expired, altered, unsafe or not this scenario's stops the
  // run here, naming the file, before any process flies.
  if (!rc.transport.keystore.empty()) {
    try {
      std::vector<AgentId> ids;
      for (const AgentSpec& a : rc.agents) ids.push_back(a.id);
      Keystore(rc.transport.keystore).check_run(ids);
    } catch (const KeystoreError& e) {
      std::cerr << "swarm run: transport.keystore: " << e.what() << "\n";
      return 2;
    }
  }
  // Every process gets its own participant id, from a block whose ports are free on this host (so
  // hundreds of processes come up without Fast DDS shifting ports, and two runs on one domain do
  // not collide); a domain without room is the user's to change.
  // The supervisor, the agents and, with Discovery Servers, the servers (the block's last ids).
  const bool own_server = rc.plan.own_server;
  const int participants = rc.plan.participants;
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
  spec.grace_s = opt.grace_s;
  spec.progress = !opt.quiet;
  spec.stop_on_agent_exit = opt.stop_on_agent_exit;
  spec.ignore_sigterm = opt.ignore_sigterm;
  spec.participant_base = *base;
  if (own_server) {
    for (int k = 0; k < rc.plan.own_servers; ++k)
      spec.discovery_ids.push_back(rc.plan.server_participant(*base, k));
    // Written by a server once its participant listens. Not its ports seen taken: the server
    // binds them briefly itself to check them first, and a probe of them from here could take
    // them in that instant.
    spec.discovery_ready = [dir](int k) { return fs::exists(dir.discovery_ready(k)); };
    spec.hung_servers = opt.hung_servers;
  }
  // What the run asks of this host, said before it flies and kept in its summary.
  spec.load = predict_load_here(rc, opt.time_scale);
  spec.view_port = opt.view_port;
  spec.view_listen = opt.view_listen;
  if (!dir.write_scenario(rc.resolved)) {
    std::cerr << "swarm run: cannot write " << dir.scenario().string() << " (disk full?)\n";
    return 3;
  }
  if (!dir.write_plan(to_proto(rc.plan, *base))) {
    std::cerr << "swarm run: cannot write " << dir.plan().string() << " (disk full?)\n";
    return 3;
  }
  if (!opt.quiet) {
    const InitialGraph g = initial_graph(rc);
    std::cout << "swarm run: " << rc.name << ", " << rc.agents.size() << " agents, domain "
              << rc.transport.domain_id << ", time scale " << opt.time_scale << ", seed " << rc.seed
              << "\n"
              << "initial graph: " << g.edges.size() << " edges, lambda2 " << g.spectrum.lambda2
              << (g.spectrum.components > 1 ? " (not connected yet)" : "") << "\n"
              << describe_load(*spec.load) << "run directory: " << dir.str() << std::endl;
  }
  if (const std::string w = load_warning(*spec.load); !w.empty())
    std::cerr << "swarm run: " << w << std::endl;

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGHUP, on_signal);
  ProcessGroup procs;
  SteadyClock clock;
  Launcher launcher(spec, procs, clock, [&] { return fs::exists(dir.supervisor_ready()); });
  try {
    launcher.start();
  } catch (const SupervisorRefused& e) {
    std::cerr << "swarm run: " << e.what() << "\n";
    launcher.stop();
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "swarm run: " << e.what() << "\n";
    launcher.stop();
    // What the teardown saw too (a server that had hung, one lost while the other served).
    std::string reason = e.what();
    for (const std::string& p : launcher.problems()) {
      std::cerr << "swarm run: " << p << "\n";
      reason += "; " + p;
    }
    for (const std::string& n : launcher.notes()) std::cerr << "swarm run: " << n << "\n";
    if (dir.write_fallback_summary(rc, reason, clock.now_s())) {
      dir.note_load(*spec.load);
      dir.add_notes(launcher.notes());
    }
    return 1;
  }
  if (opt.view_port >= 0 && opt.quiet) {
    // Without the live line the supervisor's own announcement goes to supervisor.out.
    if (const std::string url = dir.read_view_url(); !url.empty())
      std::cout << "swarm run: live view on " << url << std::endl;
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

}  // namespace

Command add_run_command(CLI::App& app) {
  auto o = std::make_shared<RunOptions>();
  CLI::App* cmd =
      app.add_subcommand("run", "launch the supervisor and one agent process per agent");
  cmd->add_option("scenario", o->scenario, "scenario file (Protobuf text format)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "run directory to create (default runs/TIMESTAMP-NAME)");
  cmd->add_option("--agents", o->agents, "fly N agents from seeded random positions")
      ->check(CLI::Range(1, 512));
  cmd->add_option("--seed", o->seed, "seed (overrides the scenario)")
      ->check(CLI::Range(std::int64_t{0}, std::int64_t{4294967295}));
  cmd->add_option("--duration", o->duration, "simulated seconds before giving up")
      ->check(finite_range(1e-3, 1e7));
  cmd->add_option("--time-scale", o->time_scale, "simulated seconds per wall second (default 1)")
      ->check(finite_range(0.01, 100.0));
  cmd->add_option("--domain", o->domain, "DDS domain id (overrides the scenario)")
      ->check(CLI::Range(0, static_cast<int>(PortPlan::kMaxDomain)));
  cmd->add_option("--grace", o->grace_s, "seconds between SIGTERM and SIGKILL at teardown")
      ->check(finite_range(0.0, 600.0));
  cmd->add_flag("--quiet", o->quiet, "no progress line");
  cmd->add_option("--view", o->view_port,
                  "serve the live view on http://127.0.0.1:PORT/ (default 8765; 0: any free "
                  "port; give it after SCENARIO)")
      ->expected(0, 1)
      ->default_str("8765")
      ->check(CLI::Range(0, 65535));
  cmd->add_option("--view-listen", o->view_listen,
                  "address the live view listens on (default 127.0.0.1: this host only)");
  cmd->add_flag("--stop-on-agent-exit", o->stop_on_agent_exit, "end the run when any agent exits");
  cmd->add_option("--secure", o->secure,
                  "DDS-Security with this keystore (swarm keys SCENARIO --out DIR writes one)");
  cmd->add_option("--law", o->law,
                  "agreement law, any `swarm laws` lists (overrides the scenario's and its "
                  "parameters)")
      ->check(CLI::Validator(
          [](const std::string& v) { return v.empty() ? std::string("an empty law name") : ""; },
          "LAW"));
  cmd->add_option("--plant", o->plant,
                  "the vehicle, any `swarm plants` lists (overrides the scenario's; another "
                  "plant drops its parameters and avoidance switch)")
      ->check(CLI::Validator(
          [](const std::string& v) { return v.empty() ? std::string("an empty plant name") : ""; },
          "PLANT"));
  cmd->add_option("--loss", o->loss, "fault: drop each received message with this probability")
      ->check(finite_range(0.0, 1.0))
      ->allow_extra_args(false)
      ->group("Faults");
  cmd->add_option("--cut", o->cuts, "fault: cut link A-B over a window, e.g. 1-2@5:15 (repeatable)")
      ->allow_extra_args(false)
      ->group("Faults");
  cmd->add_option("--partition", o->partitions,
                  "fault: cut group off from the rest, e.g. 1,2,3@5:15")
      ->allow_extra_args(false)
      ->group("Faults");
  cmd->add_option("--delay", o->delay,
                  "fault: delay every message MEAN[:JITTER] seconds, e.g. 0.05:0.02")
      ->allow_extra_args(false)
      ->group("Faults");
  cmd->add_option("--kill", o->kills, "fault: SIGKILL agent ID at AT, restart at RESTART: 3@10:20")
      ->allow_extra_args(false)
      ->group("Faults");
  cmd->add_option(
         "--transport-loss", o->transport_loss,
         "fault below the application: Fast DDS test transport drops this % of data messages")
      ->check(CLI::Range(0, 100))
      ->allow_extra_args(false)
      ->group("Faults");
  cmd->add_option("--random-cuts", o->random_cuts,
                  "fault: N seeded random link cuts of 1-5 s, in the first 75% of the run")
      ->check(CLI::Range(0, 10000))
      ->allow_extra_args(false)
      ->group("Faults");
  cmd->add_option("--test-ignore-sigterm", o->ignore_sigterm, "(tests) agents that ignore SIGTERM")
      ->group("");
  cmd->add_option("--test-hung-server", o->hung_servers,
                  "(tests) the run's Discovery Servers (0, 1) that stop once they listen")
      ->check(CLI::NonNegativeNumber)
      ->group("");

  return [cmd, o]() -> std::optional<int> {
    if (!*cmd) return std::nullopt;
    if (cmd->count("--view-listen") > 0 && o->view_port < 0) {
      std::cerr << "swarm run: --view-listen " << o->view_listen
                << ": says where the live view listens, and there is none: add --view [PORT]\n";
      return 2;
    }
    return run(*o);
  };
}

}  // namespace qswarm
