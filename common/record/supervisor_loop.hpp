#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "common/clock/clock.hpp"
#include "common/record/recorder.hpp"
#include "common/record/run_dir.hpp"
#include "common/scenario/run_config.hpp"
#include "common/transport/neighbor_bus.hpp"

namespace qswarm {

struct SupervisorOptions {
  double time_scale = 1.0;  // simulated seconds per wall second
  // Wall seconds to wait for the first running agent, beyond the duration (-1: the agents' own
  // start timeout, RunConfig::start_timeout_s).
  double start_timeout_s = -1.0;
  bool progress = false;        // a live line once a second and whenever the graph changes
  double poll_period_s = 0.02;  // how often the recorder does its periodic work
  double progress_period_s = 1.0;
  // Samples the inbox holds between two polls (see SupervisorLoop).
  std::size_t inbox_max = std::size_t{1} << 16;
};

// The supervisor as a unit: it listens on a transport it only reads (a DDS participant without a
// writer, or an in-memory endpoint that never publishes), feeds every accepted sample to the
// recorder, does the recorder's periodic work on the injected clock, says when the run is over and
// why, and writes the record at the end. swarm-supervisor polls it on a SteadyClock over DDS; the
// in-process swarm polls it on the swarm's ManualClock, so in-process tests end with the real
// convergence judgement and summary.
//
// A sample is stamped with its arrival time and put in an inbox; each poll records the inbox first.
// So the transport's thread never waits for the recorder (a graph snapshot of hundreds of agents
// takes milliseconds, its files may block): a supervisor short of CPU falls behind in memory, on
// the samples' own arrival times, instead of leaving datagrams to overflow its sockets. The inbox
// holds at most SupervisorOptions::inbox_max samples; beyond that they are counted, said, and not
// recorded (the record counts them as gaps).
class SupervisorLoop {
 public:
  SupervisorLoop(const RunConfig& rc, RunDir dir, SupervisorOptions opts, NeighborBus& bus,
                 Clock& clock);
  ~SupervisorLoop();
  SupervisorLoop(const SupervisorLoop&) = delete;
  SupervisorLoop& operator=(const SupervisorLoop&) = delete;

  // Says that the reader is up (supervisor.ready, which the launcher waits for). False if that
  // file could not be written.
  bool announce_ready();

  struct Poll {
    std::optional<std::string> progress;    // a live line to print
    std::optional<std::string> end_reason;  // the run is over: why
    std::vector<std::string> warnings;      // for the log: forgeries first noticed
    double wake_at_s = 0.0;
  };
  // One pass: the recorder's periodic work, what the transport refused, the live line, the end
  // conditions (the recorder's verdict, `interrupted`, no agent after the start timeout).
  Poll poll(bool interrupted);
  // Polls until the run is over (`stop` set: interrupted), sleeping on the clock in between;
  // warnings and live lines go to the callbacks. Returns why it ended.
  std::string run(const std::atomic<bool>& stop,
                  const std::function<void(const std::string&)>& warn,
                  const std::function<void(const std::string&)>& progress);
  // Stops listening and writes the end of the record and summary.json; returns the summary for
  // people. Call once, after poll() returned an end reason (or at any time, to stop early).
  std::string finish(const std::string& reason);

  // Shows the record to a watcher (the live view) as it is written; nullptr: none. Not owned.
  void set_observer(RunObserver* observer) {
    std::lock_guard<std::mutex> lock(mu_);
    recorder_.set_observer(observer);
  }

  // Samples that found the inbox full (not recorded).
  std::uint64_t inbox_overflow() const {
    std::lock_guard<std::mutex> lock(inbox_mu_);
    return overflow_;
  }

  // 0 converged with a complete record, 1 not converged, 3 the record is incomplete.
  int exit_code() const;
  bool complete() const { return recorder_.complete(); }
  const std::string& failed_file() const { return recorder_.failed_file(); }
  const Recorder& recorder() const { return recorder_; }
  const RunDir& dir() const { return dir_; }

 private:
  RunConfig rc_;
  RunDir dir_;
  SupervisorOptions opts_;
  NeighborBus& bus_;
  Clock& clock_;
  double start_s_;
  double next_progress_s_ = 0.0;
  int last_edges_ = -1;
  struct Arrival {
    StateMessage m;
    std::int64_t recv_wall_ns = 0;
  };
  // Records the inbox's samples in their order of arrival; returns the wall time at which it took
  // them (every sample that arrived before it is recorded). Called with mu_ held.
  std::int64_t record_inbox();
  mutable std::mutex inbox_mu_;  // the inbox: samples arrive on transport threads
  std::vector<Arrival> inbox_, batch_;
  std::uint64_t overflow_ = 0, overflow_said_ = 0;
  mutable std::mutex mu_;  // the recorder
  Recorder recorder_;
  bool finished_ = false;
};

}  // namespace qswarm
