#pragma once

#include <algorithm>
#include <chrono>
#include <thread>

namespace qswarm {

// Wall time as the agent loop and the launcher see it: seconds on a monotonic clock, and a way to
// wait. Injected so that tests step the loop on a ManualClock (MAVSDK's FakeTime idea): a test
// jumps seconds at once, deterministically.
class Clock {
 public:
  virtual ~Clock() = default;
  virtual double now_s() const = 0;
  // Returns at or after t_s (a ManualClock jumps there).
  virtual void sleep_until(double t_s) = 0;
};

// The process's clock: std::chrono::steady_clock, seconds since construction.
class SteadyClock final : public Clock {
 public:
  double now_s() const override {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  }
  void sleep_until(double t_s) override {
    std::this_thread::sleep_until(t0_ +
                                  std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                      std::chrono::duration<double>(t_s)));
  }

 private:
  std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();
};

// A clock that moves only when told: tests and the in-process swarm.
class ManualClock final : public Clock {
 public:
  explicit ManualClock(double t0_s = 0.0) : t_s_(t0_s) {}
  double now_s() const override { return t_s_; }
  void sleep_until(double t_s) override { t_s_ = std::max(t_s_, t_s); }
  void advance(double dt_s) { t_s_ += std::max(0.0, dt_s); }
  void set(double t_s) { t_s_ = std::max(t_s_, t_s); }

 private:
  double t_s_;
};

}  // namespace qswarm
