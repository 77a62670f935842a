// swarm-agent: one quadcopter (or particle) as its own process with its own DDS participant. The
// AgentLoop does the work; this file parses flags, sets up logging and wires signals.
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <csignal>

#include "agent/stats.hpp"
#include "common/app/process_setup.hpp"
#include "common/runtime/agent_loop.hpp"

namespace {
std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }
// However slow the rates, a stop request is seen within this many wall seconds.
constexpr double kMaxSleepS = 0.05;
}  // namespace

int main(int argc, char** argv) {
  using namespace qswarm;
  CLI::App app{"swarm-agent: one quadcopter of the swarm, over DDS"};
  ProcessOptions opts;
  AgentLoopOptions lo;
  std::string run_dir;
  unsigned id = 0;
  bool ignore_sigterm = false;
  add_process_options(app, opts);
  app.add_option("--id", id, "this agent's id (must be listed in the scenario)")->required();
  app.add_option("--run-dir", run_dir, "directory for this agent's log");
  app.add_option("--start-timeout", lo.start_timeout_s, "wall seconds to wait for all peers")
      ->check(CLI::Range(0.0, 3600.0));
  app.add_option("--max-wall", lo.max_wall_s, "stop after this many wall seconds running")
      ->check(CLI::Range(0.0, 1e6));
  app.add_option("--join-at", lo.join_at_s, "join late: start when the swarm's clock is here")
      ->check(CLI::Range(0.0, 1e7));
  app.add_flag("--restart", lo.restarted, "a restart: recover the flows this agent owned");
  app.add_flag("--wait-supervisor", lo.wait_supervisor, "start once a supervisor has matched");
  app.add_flag("--ignore-sigterm", ignore_sigterm, "(tests) ignore SIGTERM")->group("");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  const std::optional<RunConfig> rc = load_for_process("swarm-agent", opts);
  if (!rc) return 2;
  if (!rc->agent(id)) {
    std::fprintf(stderr, "swarm-agent: --id %u: expected the id of an agent listed in %s\n", id,
                 opts.scenario.c_str());
    return 2;
  }
  const std::string name = "agent-" + std::to_string(id);
  auto log = make_process_logger(name, run_dir.empty() ? "" : run_dir + "/" + name + ".log");
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, ignore_sigterm ? SIG_IGN : on_signal);
  try {
    SteadyClock clock;
    DdsBus bus(dds_options(*rc, "swarm-" + name, opts.interface));
    lo.time_scale = opts.time_scale;
    lo.incarnation = wall_now_ns();
    lo.wall_clock_ns = wall_now_ns;
    AgentLoop loop(*rc, id, lo, bus, clock);
    log->info("agent {} up: domain {}, {} law, time scale {}", id, rc->domain_id,
              to_string(rc->law.kind), opts.time_scale);
    while (!g_stop) {
      const AgentLoop::Poll p = loop.poll();
      for (const auto& n : p.notes)
        log->log(n.warning ? spdlog::level::warn : spdlog::level::info, n.text);
      if (p.kill) {
        log->warn("t={:.3f} s: planned kill: SIGKILL to myself", loop.runtime().time_s());
        log->flush();
        std::raise(SIGKILL);
      }
      if (p.done) break;
      clock.sleep_until(std::min(p.wake_at_s, clock.now_s() + kMaxSleepS));
    }
    loop.stop();
    log->info(final_report(loop, bus.counters()));
    if (!run_dir.empty())
      write_stats(run_dir + "/" + name + ".stats", loop, bus.counters(), clock.now_s());
  } catch (const std::exception& e) {
    log->error("fatal: {}", e.what());
    return 1;
  }
  return 0;
}
