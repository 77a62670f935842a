#include "common/app/supervisor_app.hpp"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <stdexcept>

#include "common/app/cli_checks.hpp"

#include "common/record/scene.hpp"
#include "common/view/view_model.hpp"

namespace qswarm {

void add_supervisor_options(CLI::App& app, SupervisorFlags& f) {
  add_process_options(app, f.process);
  auto* rd = app.add_option("--run-dir", f.run_dir, "run directory to write (swarm run's)")
                 ->check(CLI::ExistingDirectory);
  app.add_option("--new-run-in", f.new_run_in,
                 "create a fresh run directory ROOT/TIMESTAMP-NAME and record there (compose)")
      ->excludes(rd);
  app.add_option("--start-timeout", f.loop.start_timeout_s,
                 "wall seconds to wait for the first agent beyond the duration (default: the run "
                 "plan's)")
      ->check(finite_range(0.0, 3600.0));
  app.add_flag("--progress", f.loop.progress, "print a live progress line");
  app.add_option("--view", f.view_port,
                 "serve the live view (page and Foxglove WebSocket) on this port; 0: any free port")
      ->envname("QSWARM_VIEW")
      ->check(CLI::Range(0, 65535));
  app.add_option("--view-listen", f.view_listen,
                 "address the live view listens on (default 127.0.0.1: this host only)")
      ->envname("QSWARM_VIEW_LISTEN");
}

RunDir new_run_dir(const std::string& root, const RunConfig& rc) {
  RunDir dir = RunDir::claim("", rc.name, run_timestamp(), root, "--new-run-in");
  if (!dir.write_scenario(rc.resolved))
    throw RunDirError(dir.scenario().string() + ": cannot write");
  if (!dir.write_plan(to_proto(rc.plan))) throw RunDirError(dir.plan().string() + ": cannot write");
  return dir;
}

SupervisorView::SupervisorView(int port, const std::string& listen, const RunConfig& rc,
                               const RunDir& dir, SupervisorLoop& loop,
                               std::shared_ptr<spdlog::logger> log)
    : loop_(loop), log_(std::move(log)) {
  ViewServerOptions vo;
  vo.address = listen;
  vo.port = static_cast<std::uint16_t>(port);
  vo.name = "quadswarm " + rc.name;
  vo.log = [l = log_](const std::string& s) { l->warn("{}", s); };
  server_ = std::make_unique<ViewServer>(vo, feed_, run_info_json(rc), SceneSettings::of(rc));
  server_->start();
  loop_.set_observer(&feed_);
  std::printf("swarm-supervisor: live view on %s\n", server_->url().c_str());
  std::fflush(stdout);
  log_->info("live view on {}", server_->url());
  if (!dir.write_view_url(server_->url())) log_->error("cannot write {}", dir.view_url().string());
}

void SupervisorView::close() {
  server_->flush(1.0);
  loop_.set_observer(nullptr);
  server_->stop();
  log_->info("live view: {}; feed {} records, {} dropped", server_->counts().json(),
             feed_.counts().records, feed_.counts().dropped);
}

}  // namespace qswarm
