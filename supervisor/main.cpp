// swarm-supervisor: subscribes to every agent's state and records the run. It publishes nothing an
// agent acts on (its participant has no writer). Exit 0 when every expected agent converged and
// the record is complete, 1 when the run ended otherwise (duration, interrupted, an agent
// missing), 2 for bad input, 3 when a file of the record could not be written.
#include <spdlog/sinks/basic_file_sink.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <thread>

#include "common/app/cli_checks.hpp"
#include "common/app/process_setup.hpp"
#include "common/record/recorder.hpp"
#include "common/record/run_dir.hpp"
#include "common/runtime/agent_loop.hpp"

namespace {
std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }
}  // namespace

int main(int argc, char** argv) {
  using namespace qswarm;
  exit_cleanly_on_uncaught_exceptions("swarm-supervisor");
  CLI::App app{"swarm-supervisor: records a swarm run (telemetry, graph, events, summary)"};
  ProcessOptions opts;
  std::string run_dir;
  bool progress = false;
  double start_timeout_s = -1.0;
  add_process_options(app, opts);
  std::string new_run_in;
  auto* rd = app.add_option("--run-dir", run_dir, "run directory to write");
  app.add_option("--new-run-in", new_run_in,
                 "create a fresh run directory ROOT/TIMESTAMP-NAME and record there (compose)")
      ->excludes(rd);
  app.add_option("--start-timeout", start_timeout_s,
                 "wall seconds to wait for the first agent (default 30 + 0.5 per agent)")
      ->check(finite_range(0.0, 3600.0));
  app.add_flag("--progress", progress, "print a live progress line");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  const std::optional<RunConfig> loaded = load_for_process("swarm-supervisor", opts);
  if (!loaded) return 2;
  const RunConfig& rc = *loaded;
  if (start_timeout_s < 0.0) start_timeout_s = default_start_timeout_s(rc.agents.size());
  if (run_dir.empty() == new_run_in.empty()) {
    std::fprintf(stderr, "swarm-supervisor: give --run-dir DIR or --new-run-in ROOT\n");
    return 2;
  }
  if (!new_run_in.empty()) {
    try {
      run_dir = claim_run_dir("", rc.name, run_timestamp(), new_run_in).string();
      std::ofstream scen(run_dir + "/scenario.txtpb");
      scen << "# The scenario as run (defaults filled in, agents listed).\n"
           << to_text(rc.resolved);
      if (!scen.flush()) throw RunDirError(run_dir + "/scenario.txtpb: cannot write");
    } catch (const std::exception& e) {
      std::fprintf(stderr, "swarm-supervisor: --new-run-in %s: %s\n", new_run_in.c_str(), e.what());
      return 3;
    }
    std::printf("swarm-supervisor: recording into %s\n", run_dir.c_str());
    std::fflush(stdout);
  }
  auto logger = spdlog::basic_logger_mt("supervisor", run_dir + "/supervisor.log", true);
  logger->flush_on(spdlog::level::info);
  spdlog::set_default_logger(logger);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);

  const auto wall0 = std::chrono::steady_clock::now();
  const auto wall_s = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  };
  try {
    Recorder rec(rc, run_dir, opts.time_scale);
    std::mutex mu;
    DdsOptions dopt = dds_options(rc, "swarm-supervisor", opts);
    dopt.publish = false;  // a read-only participant: it publishes nothing an agent acts on
    dopt.test_drop_data_percent = 0;
    dopt.hear_all_runs = true;  // so that another run on this domain is seen, and said
    DdsBus bus(dopt);
    bus.set_listener([&](const StateMessage& m) {
      const std::int64_t recv_ns = wall_now_ns();
      std::lock_guard<std::mutex> lock(mu);
      rec.on_sample(m, recv_ns);
    });
    logger->info("supervisor up on domain {}, expecting {} agents", rc.transport.domain_id,
                 rc.agents.size());
    std::ofstream(run_dir + "/supervisor.ready") << "reader up\n";  // the launcher waits for this
    std::string reason;
    double last_print = -1.0;
    int last_edges = 0;
    while (true) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      std::lock_guard<std::mutex> lock(mu);
      rec.tick(wall_now_ns());
      rec.note_foreign_runs(bus.foreign_runs(), bus.counters().foreign);
      rec.note_strangers(bus.strangers());
      // Once a second, and whenever the graph gains or loses an edge.
      if (progress && (wall_s() - last_print >= 1.0 || rec.edges_now() != last_edges)) {
        last_edges = rec.edges_now();
        std::printf("%s\n", rec.progress_line().c_str());
        std::fflush(stdout);
        last_print = wall_s();
      }
      reason = rec.end_reason_if_over();
      if (!reason.empty()) break;
      if (g_stop) {
        reason = "interrupted";
        break;
      }
      if (rec.time_s() == 0.0 &&
          wall_s() > start_timeout_s + rc.judge.duration_s / opts.time_scale) {
        reason = "no agents running";
        break;
      }
    }
    bus.set_listener(nullptr);
    std::lock_guard<std::mutex> lock(mu);
    const std::string text = rec.finish(reason, wall_s());
    std::printf("%s", text.c_str());
    std::fflush(stdout);
    logger->info("finished: {}", reason);
    if (!rec.complete()) {
      std::fprintf(stderr, "swarm-supervisor: the run record is incomplete: could not write %s\n",
                   rec.failed_file().c_str());
      logger->error("run record incomplete: could not write {}", rec.failed_file());
      return 3;
    }
    return rec.converged() ? 0 : 1;
  } catch (const std::exception& e) {
    const std::string what = describe_exception(e);
    std::fprintf(stderr, "swarm-supervisor: %s\n", what.c_str());
    logger->error("fatal: {}", what);
    return 1;
  }
}
