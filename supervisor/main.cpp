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
#include <fstream>
#include <memory>

#include "common/app/cli_checks.hpp"
#include "common/app/process_setup.hpp"
#include "common/record/run_dir.hpp"
#include "common/record/supervisor_loop.hpp"
#include "common/view/view_model.hpp"
#include "common/view/view_server.hpp"

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
                 "wall seconds to wait for the first agent beyond the duration (default 30 + 0.5 "
                 "per agent)")
      ->check(finite_range(0.0, 3600.0));
  app.add_flag("--progress", progress, "print a live progress line");
  int view_port = -1;
  std::string view_listen = "127.0.0.1";
  app.add_option("--view", view_port,
                 "serve the live view (page and Foxglove WebSocket) on this port; 0: any free port")
      ->envname("QSWARM_VIEW")
      ->check(CLI::Range(0, 65535));
  app.add_option("--view-listen", view_listen,
                 "address the live view listens on (default 127.0.0.1: this host only)")
      ->envname("QSWARM_VIEW_LISTEN");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  const std::optional<RunConfig> loaded = load_for_process("swarm-supervisor", opts);
  if (!loaded) return 2;
  const RunConfig& rc = *loaded;
  if (!rc.transport.keystore.empty()) {
    std::string why;
    if (keystore_identity(rc.transport.keystore, "supervisor", why).empty()) {
      std::fprintf(stderr, "swarm-supervisor: transport.keystore: %s\n", why.c_str());
      return 2;
    }
  }
  if (run_dir.empty() == new_run_in.empty()) {
    std::fprintf(stderr, "swarm-supervisor: give --run-dir DIR or --new-run-in ROOT\n");
    return 2;
  }
  RunDir dir(run_dir);
  if (!new_run_in.empty()) {
    try {
      dir = RunDir::claim("", rc.name, run_timestamp(), new_run_in, "--new-run-in");
      if (!dir.write_scenario(rc.resolved))
        throw RunDirError(dir.scenario().string() + ": cannot write");
    } catch (const std::exception& e) {
      std::fprintf(stderr, "swarm-supervisor: --new-run-in %s: %s\n", new_run_in.c_str(), e.what());
      return 3;
    }
    std::printf("swarm-supervisor: recording into %s\n", dir.str().c_str());
    std::fflush(stdout);
  }
  auto logger = spdlog::basic_logger_mt("supervisor", dir.supervisor_log().string(), true);
  logger->flush_on(spdlog::level::info);
  spdlog::set_default_logger(logger);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGHUP, on_signal);  // a hangup ends the run "interrupted", with the record written

  try {
    SteadyClock clock;
    DdsOptions dopt = dds_options(rc, "swarm-supervisor", opts);
    dopt.participant.identity = "supervisor";
    if (!opts.peer_hosts.empty()) {
      dopt.participant.unicast_peer_hosts =
          find_peer_hosts(opts.peer_hosts, rc.agents.size() + 1, kPeerHostsWaitS, g_stop,
                          [&](const std::string& line) { logger->info("{}", line); });
      if (dopt.participant.unicast_peer_hosts.empty()) {
        if (!g_stop) {
          say_peer_hosts_unresolved("swarm-supervisor", opts.peer_hosts);
          return 2;
        }
        // Stopped before any peer's name resolved: a participant that reaches no one, so that
        // the run still ends with its record ("interrupted").
        dopt.participant.unicast_peer_hosts = {"127.0.0.1"};
      }
    }
    dopt.state.publish = false;  // a read-only participant: it publishes nothing an agent acts on
    dopt.state.recorder = true;  // it reads what agents send it, not their state stream
    dopt.participant.test_drop_data_percent = 0;
    dopt.state.hear_all_runs = true;  // so that another run on this domain is seen, and said
    DdsBus bus(dopt, clock);
    SupervisorOptions so;
    so.time_scale = opts.time_scale;
    so.start_timeout_s = start_timeout_s;
    so.progress = progress;
    // The live view, only when asked for: without it the record path has no observer, no thread
    // and no copies. Its server runs on its own thread; the recorder hands it records through
    // the feed's bounded buffers. Declared before the loop, so that they outlive it.
    std::unique_ptr<ViewFeed> feed;
    std::unique_ptr<ViewServer> view;
    SupervisorLoop sup(rc, dir, so, bus, clock);
    if (view_port >= 0) {
      feed = std::make_unique<ViewFeed>();
      ViewServerOptions vo;
      vo.address = view_listen;
      vo.port = static_cast<std::uint16_t>(view_port);
      vo.name = "quadswarm " + rc.name;
      vo.log = [logger](const std::string& s) { logger->warn("{}", s); };
      view = std::make_unique<ViewServer>(vo, *feed, run_info_json(rc), SceneSettings::of(rc));
      try {
        view->start();
      } catch (const ViewServerError& e) {
        std::fprintf(stderr, "swarm-supervisor: --view %d: %s\n", view_port, e.what());
        logger->error("--view {}: {}", view_port, e.what());
        return 2;
      }
      sup.set_observer(feed.get());
      std::printf("swarm-supervisor: live view on %s\n", view->url().c_str());
      std::fflush(stdout);
      logger->info("live view on {}", view->url());
      std::ofstream(dir.path() / "view.url") << view->url() << "\n";
    }
    logger->info("supervisor up on domain {}, expecting {} agents", rc.transport.domain_id,
                 rc.agents.size());
    if (!sup.announce_ready())  // the launcher waits for this
      logger->error("cannot write {}", dir.supervisor_ready().string());
    std::string reason;
    while (true) {
      const SupervisorLoop::Poll p = sup.poll(g_stop);
      for (const std::string& w : p.warnings) logger->warn("{}", w);
      if (p.progress) {
        std::printf("%s\n", p.progress->c_str());
        std::fflush(stdout);
      }
      if (p.end_reason) {
        reason = *p.end_reason;
        break;
      }
      clock.sleep_until(p.wake_at_s);
    }
    const std::string text = sup.finish(reason);
    if (view) {
      view->flush(1.0);  // the end state reaches the pages before the server goes
      sup.set_observer(nullptr);
      view->stop();
      logger->info("live view: {}; feed {} records, {} dropped", view->counts().json(),
                   feed->counts().records, feed->counts().dropped);
    }
    std::printf("%s", text.c_str());
    std::fflush(stdout);
    logger->info("finished: {}", reason);
    if (!sup.complete()) {
      std::fprintf(stderr, "swarm-supervisor: the run record is incomplete: could not write %s\n",
                   sup.failed_file().c_str());
      logger->error("run record incomplete: could not write {}", sup.failed_file());
    }
    return sup.exit_code();
  } catch (const std::exception& e) {
    const std::string what = describe_exception(e);
    std::fprintf(stderr, "swarm-supervisor: %s\n", what.c_str());
    logger->error("fatal: {}", what);
    return 1;
  }
}
