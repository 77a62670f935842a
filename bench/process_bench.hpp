#pragma once
// What the multi-process floors (bench/wire_floor.cpp, bench/dds_floor.cpp) share: a monotonic
// clock and absolute sleeps on it (for one time grid across processes), a process's CPU time, and
// running one function in each of N forked processes that report a result back.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <ctime>
#include <type_traits>
#include <vector>

namespace qswarm::bench {

inline double now_s() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

inline void sleep_until(double t) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(t);
  ts.tv_nsec = static_cast<long>((t - static_cast<double>(ts.tv_sec)) * 1e9);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

// This process's user and system CPU time so far, every thread's [s].
inline double cpu_s() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return static_cast<double>(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

// Runs fly(i) for i = 0 .. n - 1, each in a process of its own forked from this one, which sends
// back the Result it returns. Returns the results that came back (fewer than n when a process
// failed), once every process has exited; an empty list when a fork failed (after reading what
// the processes already started send, so that none blocks on a full pipe).
template <class Result, class Fly>
std::vector<Result> in_processes(int n, Fly fly) {
  static_assert(std::is_trivially_copyable_v<Result>, "a result travels through a pipe");
  int pipe_fd[2];
  if (pipe(pipe_fd) != 0) return {};
  bool forked_all = true;
  for (int i = 0; i < n; ++i) {
    const pid_t pid = fork();
    if (pid < 0) {
      std::perror("fork");
      forked_all = false;
      break;
    }
    if (pid > 0) continue;
    close(pipe_fd[0]);
    const Result r = fly(i);
    if (write(pipe_fd[1], &r, sizeof r) != static_cast<ssize_t>(sizeof r)) _exit(1);
    _exit(0);
  }
  close(pipe_fd[1]);
  std::vector<Result> all;
  Result r;
  while (read(pipe_fd[0], &r, sizeof r) == static_cast<ssize_t>(sizeof r)) all.push_back(r);
  close(pipe_fd[0]);
  while (wait(nullptr) > 0) {
  }
  if (!forked_all) return {};
  return all;
}

}  // namespace qswarm::bench
