// swarm-supervisor: subscribes to every agent's state and records the run. It publishes nothing an
// agent acts on (its participant has no writer). Exit 0 when every expected agent converged and
// the record is complete, 1 when the run ended otherwise (duration, interrupted, an agent
// missing), 2 for bad input, 3 when a file of the record could not be written.
#include <spdlog/sinks/basic_file_sink.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <optional>

#include "common/app/process_dds.hpp"
#include "common/app/process_life.hpp"
#include "common/app/supervisor_app.hpp"
#include "common/security/keystore.hpp"

namespace {
std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }
}  // namespace

int main(int argc, char** argv) {
  using namespace qswarm;
  exit_cleanly_on_uncaught_exceptions("swarm-supervisor");
  CLI::App app{"swarm-supervisor: records a swarm run (telemetry, graph, events, summary)"};
  SupervisorFlags f;
  add_supervisor_options(app, f);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  const std::optional<RunConfig> rc = load_for_process("swarm-supervisor", f.process);
  if (!rc) return 2;
  if (f.run_dir.empty() == f.new_run_in.empty()) {
    std::fprintf(stderr, "swarm-supervisor: give --run-dir DIR or --new-run-in ROOT\n");
    return 2;
  }
  if (!keystore_ready("swarm-supervisor", *rc, Keystore::kSupervisor)) return 2;
  RunDir dir(f.run_dir);
  try {
    if (!f.new_run_in.empty()) dir = new_run_dir(f.new_run_in, *rc);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "swarm-supervisor: --new-run-in %s: %s\n", f.new_run_in.c_str(), e.what());
    return dynamic_cast<const RunDirError*>(&e) ? 2 : 3;
  }
  if (!f.new_run_in.empty())
    std::printf("swarm-supervisor: recording into %s\n", dir.str().c_str());
  std::fflush(stdout);
  auto log = spdlog::basic_logger_mt("supervisor", dir.supervisor_log().string(), true);
  log->flush_on(spdlog::level::info);
  spdlog::set_default_logger(log);
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) std::signal(sig, on_signal);  // ends recorded
  try {
    ProcessDds d = process_dds("swarm-supervisor", *rc, f.process, "swarm-supervisor",
                               Keystore::kSupervisor, g_stop, StoppedWaiting::kRecord,
                               [&](const std::string& line) { log->info("{}", line); });
    if (d.exit_code >= 0) return d.exit_code;
    d.options.state.publish = false;       // a read-only participant: nothing an agent acts on
    d.options.state.recorder = true;       // it reads what agents send it, not their state stream
    d.options.state.hear_all_runs = true;  // so that another run on this domain is seen, and said
    d.options.participant.test_drop_data_percent = 0;
    d.options.participant.threads_nice = rc->plan.supervisor_threads_nice;
    SteadyClock clock;
    DdsBus bus(d.options, clock);
    f.loop.time_scale = f.process.time_scale;
    SupervisorLoop sup(*rc, dir, f.loop, bus, clock);
    std::optional<SupervisorView> view;  // declared after the loop: it goes first
    try {
      if (f.view_port >= 0) view.emplace(f.view_port, f.view_listen, *rc, dir, sup, log);
    } catch (const ViewServerError& e) {
      std::fprintf(stderr, "swarm-supervisor: --view %d: %s\n", f.view_port, e.what());
      log->error("--view {}: {}", f.view_port, e.what());
      return 2;
    }
    log->info("supervisor up, expecting {} agents", rc->agents.size());
    if (!bus.participant().threads_priority().empty())
      log->info("Fast DDS's threads started with the participant run at {}",
                bus.participant().threads_priority());
    if (!sup.announce_ready()) log->error("cannot write {}", dir.supervisor_ready().string());
    const std::string reason = sup.run(
        g_stop, [&](const std::string& w) { log->warn("{}", w); },
        [](const std::string& line) { std::printf("%s\n", line.c_str()), std::fflush(stdout); });
    const std::string text = sup.finish(reason);
    if (view) view->close();
    std::printf("%s", text.c_str());
    std::fflush(stdout);
    log->info("finished: {}", reason);
    if (!sup.complete())
      std::fprintf(stderr, "swarm-supervisor: the run record is incomplete: could not write %s\n",
                   sup.failed_file().c_str());
    return sup.exit_code();
  } catch (const std::exception& e) {
    const std::string what = describe_exception(e);
    std::fprintf(stderr, "swarm-supervisor: %s\n", what.c_str());
    log->error("fatal: {}", what);
    return 1;
  }
}
