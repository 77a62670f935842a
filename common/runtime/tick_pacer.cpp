#include "common/runtime/tick_pacer.hpp"

#include <stdexcept>

namespace qswarm {

TickPacer::TickPacer(double start_wall_s, double period_wall_s)
    : start_s_(start_wall_s), period_s_(period_wall_s) {
  if (!(period_wall_s > 0.0)) throw std::invalid_argument("tick period must be > 0");
}

double TickPacer::next_due_s() const { return start_s_ + static_cast<double>(ticks_) * period_s_; }

void TickPacer::on_tick(double now_wall_s) {
  if (now_wall_s - next_due_s() > period_s_) ++overruns_;
  ++ticks_;
}

}  // namespace qswarm
