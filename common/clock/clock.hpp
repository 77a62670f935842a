#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <thread>

namespace qswarm {

// Time as the agent loop, the supervisor and the launcher see it: seconds on a monotonic clock to
// pace and wait by, the wall time that samples carry (incarnations, same-host sample ages), and a
// way to wait. Injected so that tests step them on a ManualClock (MAVSDK's FakeTime idea): a test
// jumps seconds at once, deterministically. Reading is thread-safe for SteadyClock (DDS threads
// stamp receptions); a ManualClock belongs to one thread.
class Clock {
 public:
  virtual ~Clock() = default;
  virtual double now_s() const = 0;
  // Nanoseconds since the Unix epoch.
  virtual std::int64_t wall_ns() const = 0;
  // Returns at or after t_s (a ManualClock jumps there).
  virtual void sleep_until(double t_s) = 0;
  // Where this clock's zero lies on a time line every process of the host shares (the monotonic
  // clock's): processes that align events to multiples of a period on that line act together.
  virtual double shared_origin_s() const { return 0.0; }
};

// The process's clock: std::chrono::steady_clock, seconds since construction; the wall time is
// the system clock's.
class SteadyClock final : public Clock {
 public:
  double now_s() const override {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  }
  std::int64_t wall_ns() const override {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::system_clock::now().time_since_epoch())
        .count();
  }
  void sleep_until(double t_s) override {
    std::this_thread::sleep_until(t0_ +
                                  std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                      std::chrono::duration<double>(t_s)));
  }
  double shared_origin_s() const override {
    return std::chrono::duration<double>(t0_.time_since_epoch()).count();
  }

 private:
  std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();
};

// The process's own clock, for what reads the time outside any loop (a transport's receive path).
inline const Clock& system_clock() {
  static const SteadyClock clock;
  return clock;
}

// A clock that moves only when told: tests and the in-process swarm. Its wall time runs with it
// from a fixed epoch, so what a run stamps replays exactly.
class ManualClock final : public Clock {
 public:
  // 2026-01-01T00:00:00Z: any fixed instant; only differences and order matter.
  static constexpr std::int64_t kEpochNs = 1767225600LL * 1000000000LL;
  explicit ManualClock(double t0_s = 0.0) : t_s_(t0_s) {}
  double now_s() const override { return t_s_; }
  std::int64_t wall_ns() const override {
    return kEpochNs + static_cast<std::int64_t>(std::llround(t_s_ * 1e9));
  }
  void sleep_until(double t_s) override { t_s_ = std::max(t_s_, t_s); }
  void advance(double dt_s) { t_s_ += std::max(0.0, dt_s); }
  void set(double t_s) { t_s_ = std::max(t_s_, t_s); }

 private:
  double t_s_;
};

}  // namespace qswarm
