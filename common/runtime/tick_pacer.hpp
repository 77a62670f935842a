#pragma once

#include <cstdint>

namespace qswarm {

// Real-time pacing of consensus ticks: tick k is due at start + k * period (wall seconds). A tick
// that starts more than one period after it was due counts as an overrun (a late tick). The pacer
// never skips ticks: a late loop catches up, one tick per call, without sleeping. Pure: it is told
// the time.
class TickPacer {
 public:
  TickPacer(double start_wall_s, double period_wall_s);

  // Wall time at which the next tick is due.
  double next_due_s() const;
  // Whether the next tick is due at now_wall_s.
  bool due(double now_wall_s) const { return now_wall_s >= next_due_s(); }
  // Account for running the next tick at now_wall_s (counts an overrun if it is late).
  void on_tick(double now_wall_s);

  std::uint64_t ticks() const { return ticks_; }
  std::uint64_t overruns() const { return overruns_; }
  double period_s() const { return period_s_; }
  double start_s() const { return start_s_; }

 private:
  double start_s_;
  double period_s_;
  std::uint64_t ticks_ = 0;
  std::uint64_t overruns_ = 0;
};

}  // namespace qswarm
