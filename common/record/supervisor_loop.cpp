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
  if (opts_.start_timeout_s < 0.0) opts_.start_timeout_s = rc.plan.start_timeout_s;
  bus_.set_listener([this](const StateMessage& m) {
    // The clock is read under the lock, so that the inbox is in order of arrival time and a
    // swap (record_inbox) splits it at one instant.
    std::lock_guard<std::mutex> lock(inbox_mu_);
    if (inbox_.size() < opts_.inbox_max) {
      inbox_.push_back({m, clock_.wall_ns()});
    } else {
      ++overflow_;
    }
  });
}

std::int64_t SupervisorLoop::record_inbox() {
  std::uint64_t overflow = 0;
  std::int64_t taken_ns = 0;
  {
    std::lock_guard<std::mutex> lock(inbox_mu_);
    batch_.swap(inbox_);
    overflow = overflow_;
    taken_ns = clock_.wall_ns();
  }
  for (const Arrival& a : batch_) recorder_.on_sample(a.m, a.recv_wall_ns);
  batch_.clear();  // keeps its capacity for the next swap
  if (overflow > overflow_said_) {
    recorder_.note_unrecorded(overflow - overflow_said_);
    overflow_said_ = overflow;
  }
  return taken_ns;
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
  // Departures are judged at the instant the inbox was taken: every sample that arrived before it
  // has been recorded, however long recording took (a supervisor starved of CPU records seconds
  // late, and silence is not judged from the time it caught up).
  recorder_.tick(record_inbox());
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

std::string SupervisorLoop::run(const std::atomic<bool>& stop,
                                const std::function<void(const std::string&)>& warn,
                                const std::function<void(const std::string&)>& progress) {
  for (;;) {
    const Poll p = poll(stop);
    for (const std::string& w : p.warnings) warn(w);
    if (p.progress) progress(*p.progress);
    if (p.end_reason) return *p.end_reason;
    clock_.sleep_until(p.wake_at_s);
  }
}

std::string SupervisorLoop::finish(const std::string& reason) {
  bus_.set_listener(nullptr);  // no sample arrives while the record is written
  std::lock_guard<std::mutex> lock(mu_);
  record_inbox();
  finished_ = true;
  return recorder_.finish(reason, clock_.now_s() - start_s_);
}

int SupervisorLoop::exit_code() const {
  std::lock_guard<std::mutex> lock(mu_);
  if (!recorder_.complete()) return 3;
  return finished_ && recorder_.converged() ? 0 : 1;
}

}  // namespace qswarm
