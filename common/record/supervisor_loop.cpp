#include "common/record/supervisor_loop.hpp"

#include <fstream>

namespace qswarm {

SupervisorLoop::SupervisorLoop(const RunConfig& rc, RunDir dir, SupervisorOptions opts,
                               NeighborBus& bus, Clock& clock)
    : rc_(rc),
      dir_(std::move(dir)),
      opts_(opts),
      bus_(bus),
      clock_(clock),
      start_s_(clock.now_s()),
      recorder_(rc, dir_, opts.time_scale) {
  if (opts_.start_timeout_s < 0.0) opts_.start_timeout_s = rc.start_timeout_s();
  bus_.set_listener([this](const StateMessage& m) {
    const std::int64_t recv_ns = clock_.wall_ns();
    std::lock_guard<std::mutex> lock(mu_);
    recorder_.on_sample(m, recv_ns);
  });
}

SupervisorLoop::~SupervisorLoop() { bus_.set_listener(nullptr); }

bool SupervisorLoop::announce_ready() {
  std::ofstream ready(dir_.supervisor_ready());
  ready << "reader up\n";
  return static_cast<bool>(ready.flush());
}

SupervisorLoop::Poll SupervisorLoop::poll(bool interrupted) {
  Poll p;
  const double now = clock_.now_s();
  p.wake_at_s = now + opts_.poll_period_s;
  std::lock_guard<std::mutex> lock(mu_);
  recorder_.tick(clock_.wall_ns());
  recorder_.note_foreign_runs(bus_.foreign_runs(), bus_.counters().foreign);
  recorder_.note_strangers(bus_.strangers());
  recorder_.note_suspects(bus_.suspects(), 0);
  p.warnings = recorder_.take_notes();
  if (opts_.progress && (now >= next_progress_s_ || recorder_.edges_now() != last_edges_)) {
    last_edges_ = recorder_.edges_now();
    p.progress = recorder_.progress_line();
    next_progress_s_ = now + opts_.progress_period_s;
  }
  const std::string reason = recorder_.end_reason_if_over();
  if (!reason.empty()) {
    p.end_reason = reason;
  } else if (interrupted) {
    p.end_reason = "interrupted";
  } else if (recorder_.time_s() == 0.0 &&
             now - start_s_ > opts_.start_timeout_s + rc_.judge.duration_s / opts_.time_scale) {
    p.end_reason = "no agents running";
  }
  return p;
}

std::string SupervisorLoop::finish(const std::string& reason) {
  bus_.set_listener(nullptr);  // no sample arrives while the record is written
  std::lock_guard<std::mutex> lock(mu_);
  finished_ = true;
  return recorder_.finish(reason, clock_.now_s() - start_s_);
}

int SupervisorLoop::exit_code() const {
  std::lock_guard<std::mutex> lock(mu_);
  if (!recorder_.complete()) return 3;
  return finished_ && recorder_.converged() ? 0 : 1;
}

}  // namespace qswarm
