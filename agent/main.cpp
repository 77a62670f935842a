// swarm-agent: one quadcopter (or particle) as its own process with its own DDS participant. It
// learns of other agents only from DDS samples, runs the agreement law and (in quadcopter mode)
// the tracking controller and dynamics in real time, and stops cleanly on SIGINT/SIGTERM.
#include <spdlog/sinks/basic_file_sink.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include <sys/resource.h>
#include <atomic>
#include <chrono>

#include <csignal>
#include <fstream>
#include <thread>

#include "common/runtime/agent_runtime.hpp"
#include "common/runtime/faults.hpp"
#include "common/runtime/process_setup.hpp"
#include "common/runtime/scenario.hpp"
#include "common/transport/dds_bus.hpp"

namespace {

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }

}  // namespace

int main(int argc, char** argv) {
  using namespace qswarm;
  using Clock = std::chrono::steady_clock;
  CLI::App app{"swarm-agent: one quadcopter of the swarm, over DDS"};
  ProcessOptions opts;
  std::string run_dir;
  unsigned id = 0;
  double start_timeout_s = 30.0;
  double max_wall_s = -1.0;
  bool ignore_sigterm = false;
  double join_at_s = -1.0;
  bool restarted = false;
  bool wait_supervisor = false;
  add_process_options(app, opts);
  app.add_option("--id", id, "this agent's id (must be listed in the scenario)")->required();
  app.add_option("--run-dir", run_dir, "directory for this agent's log");
  app.add_option("--start-timeout", start_timeout_s,
                 "wall seconds to wait for all peers before starting")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--max-wall", max_wall_s,
                 "stop after this many wall seconds (default: 2x duration + 30 s)");
  app.add_option("--join-at", join_at_s,
                 "join late: wait silently until the swarm's clock reaches this simulated time");
  app.add_flag("--restart", restarted,
               "this is a restart: recover the flows this agent owned from its neighbours' copies");
  app.add_flag("--wait-supervisor", wait_supervisor,
               "start only once a supervisor's reader has matched this agent's writer");
  app.add_flag("--ignore-sigterm", ignore_sigterm,
               "(tests) ignore SIGTERM to exercise the launcher's SIGKILL")
      ->group("");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }

  const std::optional<RunConfig> loaded = load_for_process("swarm-agent", opts);
  if (!loaded) return 2;
  const RunConfig& rc = *loaded;
  const AgentSpec* spec = rc.agent(id);
  if (!spec) {
    std::fprintf(stderr, "swarm-agent: --id %u: expected the id of an agent listed in %s\n", id,
                 opts.scenario.c_str());
    return 2;
  }

  std::vector<spdlog::sink_ptr> sinks;
  auto console = std::make_shared<spdlog::sinks::stderr_color_sink_mt>();
  console->set_level(spdlog::level::warn);
  sinks.push_back(console);
  if (!run_dir.empty()) {
    sinks.push_back(std::make_shared<spdlog::sinks::basic_file_sink_mt>(
        run_dir + "/agent-" + std::to_string(id) + ".log", false));  // append: a restart adds to it
  }
  auto logger =
      std::make_shared<spdlog::logger>("agent-" + std::to_string(id), sinks.begin(), sinks.end());
  logger->set_level(spdlog::level::info);
  logger->flush_on(spdlog::level::info);
  spdlog::set_default_logger(logger);

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, ignore_sigterm ? SIG_IGN : on_signal);

  try {
    DdsBus bus(dds_options(rc, "swarm-agent-" + std::to_string(id), opts.interface));
    // Faults belong to links: every sample this agent receives passes the plan (seeded per link).
    FaultyBus faulty(bus, LinkFaults(rc.faults, id, rc.seed), id);
    bus.set_sample_callback([&faulty](const StateMessage& m, std::int64_t) { faulty.deliver(m); });

    AgentParams p = make_agent_params(rc, *spec);
    std::set<AgentId> late;
    for (const auto& j : rc.faults.late_join) late.insert(j.agent);
    if (late.count(id) && join_at_s < 0) {
      for (const auto& j : rc.faults.late_join)
        if (j.agent == id) join_at_s = j.at_s;
    }
    const auto wall_start = Clock::now();
    if (join_at_s >= 0) {
      // Late join or restart: stay silent until the swarm's clock (the newest running peer's stamp)
      // reaches join_at_s, then start on that clock without a barrier.
      double swarm_t = -1.0;
      const double wait_s = join_at_s / opts.time_scale + start_timeout_s + 10.0;
      while (!g_stop && swarm_t < join_at_s) {
        for (const StateMessage& m : bus.latest(id))
          if (m.phase == kRunning) swarm_t = std::max(swarm_t, m.stamp_s);
        faulty.set_time(std::max(0.0, swarm_t));
        if (std::chrono::duration<double>(Clock::now() - wall_start).count() > wait_s) {
          logger->warn("join: the swarm's clock never reached {:.2f} s (at {:.2f} s), joining now",
                       join_at_s, swarm_t);
          break;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
      }
      p.start_time_s = std::max(0.0, swarm_t);
      p.expected_peers = 0;
      p.recover_flows = restarted;
      logger->info("{} at swarm time {:.3f} s", restarted ? "restarting" : "joining late",
                   p.start_time_s);
    }
    AgentRuntime agent(p, faulty);
    agent.set_wall_clock(wall_now_ns);
    logger->info(
        "agent {} up: domain {}, {} mode, {} law, start ({:.3f}, {:.3f}, {:.3f}), time scale {}",
        id, rc.domain_id, rc.mode == AgentMode::kQuadcopter ? "quadcopter" : "particle",
        to_string(rc.law.kind), p.p0_W.x(), p.p0_W.y(), p.p0_W.z(), opts.time_scale);

    // Start barrier: kWaiting until every other agent is heard, then kReady; run once all are
    // ready or running. Publishing every 5 ms meanwhile keeps the start skew to a few ms. The
    // barrier reads the raw transport: faults apply to the run, which starts once everyone is up.
    // (A late or restarted agent has join_at_s set and skips the barrier.)
    const std::size_t expected = join_at_s >= 0 ? 0 : rc.agents.size() - 1 - late.size();
    while (!g_stop) {
      std::size_t heard = 0, ready = 0;
      for (const StateMessage& m : bus.latest(id)) {
        if (late.count(m.view.id)) continue;
        ++heard;
        ready += (m.phase == kReady || m.phase == kRunning) ? 1 : 0;
      }
      // With a supervisor, its reader must be matched too (one more than the peers'), so it records
      // the start (the paper's initial graph lasts about two ticks).
      const bool supervised =
          !wait_supervisor || bus.matched_readers() >= static_cast<int>(expected) + 1;
      const bool all_heard = heard >= expected && supervised;
      if (all_heard && ready >= expected) break;
      if (Clock::now() - wall_start > std::chrono::duration<double>(start_timeout_s)) {
        logger->warn("start timeout: {} of {} peers ready, starting anyway", ready, expected);
        break;
      }
      agent.publish(all_heard ? kReady : kWaiting);
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    const double discovery_s = std::chrono::duration<double>(Clock::now() - wall_start).count();
    logger->info("running after {:.2f} s of discovery", discovery_s);

    if (max_wall_s < 0) max_wall_s = 2.0 * rc.duration_s / opts.time_scale + 30.0;
    // Real-time pacing per consensus tick: each tick's physics (physics_hz/consensus_hz RK4 steps
    // of 1/physics_hz simulated seconds) runs as one batch when the tick is due. Nothing outside
    // the agent can see between ticks (it publishes at ticks and its reference changes at ticks),
    // and 32 processes waking every 2 ms on two cores overran 9.5% of their deadlines.
    const int batch = agent.steps_per_tick();
    const double tick_wall_s = batch / (rc.physics_hz * opts.time_scale);
    const auto t0 = Clock::now();
    std::uint64_t k = 0, ticks = 0, overruns = 0;
    // Planned kills of this agent (not those before this process started: it is their restart).
    std::vector<double> kills;
    for (const auto& kill : rc.faults.kill)
      if (kill.agent == id && kill.at_s >= agent.time_s()) kills.push_back(kill.at_s);
    while (!g_stop) {
      const auto due =
          t0 + std::chrono::duration_cast<Clock::duration>(
                   std::chrono::duration<double>(static_cast<double>(ticks) * tick_wall_s));
      const auto now = Clock::now();
      if (now < due) {
        std::this_thread::sleep_until(due);
      } else if (now - due > std::chrono::duration<double>(tick_wall_s)) {
        ++overruns;  // this tick started more than one tick period late
      }
      const BusCounters c = bus.counters();
      agent.set_counters(c.received, c.dropped + c.stale, overruns);
      agent.set_fault_counters(faulty.counters());
      faulty.set_time(agent.time_s());
      for (double at : kills) {
        if (agent.time_s() >= at) {
          logger->warn("t={:.3f} s: planned kill: SIGKILL to myself", agent.time_s());
          logger->flush();
          std::raise(SIGKILL);
        }
      }
      for (int i = 0; i < batch; ++i, ++k) {
        for (const AgentEvent& e : agent.step()) {
          logger->info(
              "t={:.3f} s: neighbour {} {}", e.t_s, e.peer,
              e.kind == AgentEvent::kNeighborHeard ? "heard" : "lost (silent past timeout)");
        }
      }
      ++ticks;
      if (std::chrono::duration<double>(Clock::now() - t0).count() > max_wall_s) {
        logger->warn("max wall time reached, stopping");
        break;
      }
    }
    agent.publish(kStopping);
    const BusCounters c = bus.counters();
    const Vec3 q = agent.consensus(), x = agent.position();
    logger->info(
        "stopping at t={:.3f} s: consensus ({:.6f}, {:.6f}, {:.6f}) position ({:.6f}, {:.6f}, "
        "{:.6f}); "
        "published {}, received {}, dropped {}, stale {}, late ticks {} of {} ({} physics steps); "
        "flows recovered at restart {}",
        agent.time_s(), q.x(), q.y(), q.z(), x.x(), x.y(), x.z(), c.published, c.received,
        c.dropped, c.stale, overruns, ticks, k, agent.recovered_flows());
    if (!run_dir.empty()) {
      // Machine-readable stats for bench/swarm_scale.sh.
      rusage ru{};
      getrusage(RUSAGE_SELF, &ru);
      const double cpu_s = static_cast<double>(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
                           static_cast<double>(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec) * 1e-6;
      std::ofstream(run_dir + "/agent-" + std::to_string(id) + ".stats")
          << "cpu_s " << cpu_s << "\nwall_s "
          << std::chrono::duration<double>(Clock::now() - t0).count() << "\nsteps " << ticks
          << "\nphysics_steps " << k << "\noverruns " << overruns << "\ndiscovery_s " << discovery_s
          << "\nmax_rss_kb " << ru.ru_maxrss << "\nreceived " << c.received << "\ndropped "
          << c.dropped << "\n";
    }
  } catch (const std::exception& e) {
    logger->error("fatal: {}", e.what());
    return 1;
  }
  return 0;
}
