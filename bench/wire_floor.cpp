// The floor under an agent process: N processes that do only what an agent of a ring swarm must
// do on the wire, with no DDS and no simulation. Each ticks at RATE_HZ on one shared time grid
// and sends a BYTES-long datagram to each of its DEGREE ring neighbours over UDP on loopback;
// what its neighbours send it is received either by a thread blocked in recv (as a DDS
// participant's receive thread does: `thread`) or drained without blocking at each tick (`drain`,
// one wake-up per tick). Reports each process's CPU (median, max), late ticks (a tick that starts
// more than one period late) and datagrams received per process per second. What an agent costs
// beyond this is the middleware's and the simulation's, not the kernel's.
// Usage: wire_floor N [SECONDS=20] [RATE_HZ=50] [thread|drain] [DEGREE=4] [BYTES=600]
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "bench/process_bench.hpp"

namespace {

using qswarm::bench::now_s;
using qswarm::bench::sleep_until;

struct Result {
  double cpu_s = 0.0;
  long ticks = 0, late = 0, received = 0;
};

Result fly(int fd, const std::vector<sockaddr_in>& to, double start, double seconds, double hz,
           bool drain, std::size_t bytes) {
  std::atomic<long> received{0};
  std::atomic<bool> stop{false};
  std::vector<char> out(bytes, 'q'), in(65536);
  std::thread reader;
  if (!drain) {
    timeval tv{0, 100000};  // wakes to notice the end
    setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    reader = std::thread([&] {
      while (!stop) {
        if (recv(fd, in.data(), in.size(), 0) > 0) ++received;
      }
    });
  }
  Result r;
  const double period = 1.0 / hz;
  for (long k = 0; start + static_cast<double>(k) * period < start + seconds; ++k) {
    const double due = start + static_cast<double>(k) * period;
    sleep_until(due);
    if (now_s() - due > period) ++r.late;
    ++r.ticks;
    if (drain)
      while (recv(fd, in.data(), in.size(), MSG_DONTWAIT) > 0) ++received;
    for (const sockaddr_in& a : to)
      sendto(fd, out.data(), out.size(), 0, reinterpret_cast<const sockaddr*>(&a), sizeof a);
  }
  stop = true;
  if (reader.joinable()) reader.join();
  r.cpu_s = qswarm::bench::cpu_s();
  r.received = received;
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: wire_floor N [SECONDS=20] [RATE_HZ=50] [thread|drain] [DEGREE=4] "
                 "[BYTES=600]\n");
    return 2;
  }
  const int n = std::atoi(argv[1]);
  const double seconds = argc > 2 ? std::atof(argv[2]) : 20.0;
  const double hz = argc > 3 ? std::atof(argv[3]) : 50.0;
  const std::string mode = argc > 4 ? argv[4] : "thread";
  const bool drain = mode == "drain";
  const int degree = argc > 5 ? std::atoi(argv[5]) : 4;
  const long bytes = argc > 6 ? std::atol(argv[6]) : 600;
  const char* bad = nullptr;
  if (n < 2 || n > 4096) {
    bad = "N: 2 to 4096 processes";
  } else if (!(seconds > 0.0 && seconds <= 3600.0)) {
    bad = "SECONDS: above 0, at most 3600";
  } else if (!(hz > 0.0 && hz <= 1000.0)) {
    bad = "RATE_HZ: above 0, at most 1000";
  } else if (mode != "thread" && mode != "drain") {
    bad = "the receive mode: thread or drain";
  } else if (degree < 1 || degree >= n) {
    bad = "DEGREE: 1 to N - 1";
  } else if (bytes < 1 || bytes > 60000) {
    bad = "BYTES: 1 to 60000";
  }
  if (bad) {
    std::fprintf(stderr, "wire_floor: %s\n", bad);
    return 2;
  }
  // Every socket is bound (to a port the kernel picks) before any process starts, so that each
  // knows its neighbours' addresses; no planned port can collide with another run's.
  std::vector<int> fds(static_cast<std::size_t>(n));
  std::vector<sockaddr_in> addr(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const int fd = socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof a;
    if (fd < 0 || bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 ||
        getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) != 0) {
      std::perror("wire_floor: socket");
      return 1;
    }
    fds[static_cast<std::size_t>(i)] = fd;
    addr[static_cast<std::size_t>(i)] = a;
  }
  const double start = std::ceil(now_s()) + 1.0 + 0.002 * n;  // after every fork
  const std::vector<Result> all = qswarm::bench::in_processes<Result>(n, [&](int i) {
    for (int j = 0; j < n; ++j)
      if (j != i) close(fds[static_cast<std::size_t>(j)]);
    std::vector<sockaddr_in> to;
    for (int d = 1; d <= degree; ++d) {  // +1, -1, +2, -2, ...
      const int off = (d + 1) / 2 * (d % 2 ? 1 : -1);
      to.push_back(addr[static_cast<std::size_t>(((i + off) % n + n) % n)]);
    }
    return fly(fds[static_cast<std::size_t>(i)], to, start, seconds, hz, drain,
               static_cast<std::size_t>(bytes));
  });
  if (static_cast<int>(all.size()) != n) {
    std::fprintf(stderr, "wire_floor: %zu of %d processes reported\n", all.size(), n);
    return 1;
  }
  std::vector<double> cpu;
  long ticks = 0, late = 0, received = 0;
  for (const Result& x : all) {
    cpu.push_back(100.0 * x.cpu_s / seconds);
    ticks += x.ticks;
    late += x.late;
    received += x.received;
  }
  std::sort(cpu.begin(), cpu.end());
  std::printf("| %d | %s | %.0f | %d | %zu | %.2f | %.2f | %.2f | %.0f |\n", n,
              drain ? "drain" : "thread", hz, degree, bytes, cpu[cpu.size() / 2], cpu.back(),
              100.0 * static_cast<double>(late) / static_cast<double>(ticks),
              static_cast<double>(received) / seconds / n);
  return 0;
}
