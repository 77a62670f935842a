#include "launcher/view_command.hpp"

#include "launcher/commands.hpp"

#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <iomanip>
#include <iostream>
#include <thread>

#include <CLI/CLI.hpp>

#include <memory>

#include "common/view/replay.hpp"
#include "common/view/view_server.hpp"

namespace qswarm {
namespace {
std::atomic<int> g_view_signal{0};
void on_view_signal(int s) { g_view_signal = s; }
}  // namespace

int view_command(const ViewCommandOptions& o) {
  if (!std::isfinite(o.speed) || o.speed <= 0.0 || o.speed > ReplayPlayback::kMaxSpeed) {
    std::cerr << "swarm view: --speed " << std::setprecision(15) << o.speed
              << ": expected a number above 0 and at most 1000\n";
    return 2;
  }
  ReplayRun run;
  try {
    run = load_replay(o.run_dir);
  } catch (const ReplayError& e) {
    std::cerr << "swarm view: RUN_DIR: " << e.what() << "\n";
    return 2;
  }
  ReplayPlayback playback(run, o.speed);
  ViewFeed unused;  // a replay feeds the view through its playback
  ViewServerOptions vo;
  vo.address = o.listen;
  vo.port = static_cast<std::uint16_t>(o.port);
  vo.name = "quadswarm replay of " + o.run_dir;
  vo.log = [](const std::string& s) { std::cerr << "swarm view: " << s << "\n"; };
  ViewServer server(vo, unused, run.run_info, run.scene, &playback);
  try {
    server.start();
  } catch (const ViewServerError& e) {
    std::cerr << "swarm view: --port " << o.port << " / --listen " << o.listen << ": " << e.what()
              << "\n";
    return 2;
  }
  std::cout << "swarm view: " << run.records.size() << " records, " << playback.duration_s()
            << " s of the run at " << o.speed << "x"
            << (run.note.empty() ? "" : " (" + run.note + ")") << "\nswarm view: open "
            << server.url() << " (Foxglove: ws://" << server.url().substr(7) << "); Ctrl-C stops"
            << std::endl;
  std::signal(SIGINT, on_view_signal);
  std::signal(SIGTERM, on_view_signal);
  std::signal(SIGHUP, on_view_signal);
  while (g_view_signal == 0) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  server.stop();
  std::cout << "swarm view: stopped; " << server.counts().json() << std::endl;
  return 0;
}

Command add_view_command(CLI::App& app) {
  auto o = std::make_shared<ViewCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "view", "replay a recorded run in the live view (browser page, Foxglove WebSocket)");
  cmd->add_option("run_dir", o->run_dir, "run directory written by swarm run")->required();
  cmd->add_option("--speed", o->speed, "simulated seconds per wall second (default 1)");
  cmd->add_option("--port", o->port, "port (default 8765; 0: any free port)")
      ->check(CLI::Range(0, 65535));
  cmd->add_option("--listen", o->listen, "address (default 127.0.0.1: this host only)");
  return [cmd, o]() -> std::optional<int> {
    if (!*cmd) return std::nullopt;
    return view_command(*o);
  };
}

}  // namespace qswarm
