// Does a Discovery Server survive clients that keep arriving while the host is busy? Fast DDS 2.9.1
// (Debian's, assertions kept) aborts a server whose timed announcement goes to a client that it
// has put in its database but not yet matched: the UDP transport's statistics assert on the
// client's locator, for which no output channel is open yet (OutputTrafficManager.hpp:87).
// This starts a server (the project's `DiscoveryServer`, or a plain Fast DDS server announcing
// every PERIOD_MS) at nice 10, two busy loops at nice 0, and two processes that each bring CLIENTS
// client participants up and down again every 300 ms, for SECONDS; then says whether the server
// lived. Exit 0: it lived; 1: it died (its signal is printed).
// Usage: ds_abort_stress project|PERIOD_MS [SECONDS=30] [CLIENTS=30] [DOMAIN=21]
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include <fastdds/rtps/attributes/ServerAttributes.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>

#include "common/dds/discovery_server.hpp"
#include "common/transport/port_plan.hpp"

namespace {

namespace dds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastdds::rtps;
using eprosima::fastrtps::rtps::IPLocator;
using eprosima::fastrtps::rtps::Locator_t;

constexpr int kServerId = 500;  // far above the ids Fast DDS gives the clients (0 up)

Locator_t loopback(std::uint16_t port) {
  Locator_t loc;
  IPLocator::setIPv4(loc, "127.0.0.1");
  loc.port = port;
  return loc;
}

// A server as Fast DDS makes one by default, but for its announcement period.
[[noreturn]] void timed_server(std::uint32_t domain, std::uint16_t port, double period_ms) {
  dds::DomainParticipantQos q;
  q.transport().use_builtin_transports = false;
  q.transport().user_transports.push_back(std::make_shared<rtps::UDPv4TransportDescriptor>());
  q.wire_protocol().builtin.use_WriterLivelinessProtocol = false;
  auto& d = q.wire_protocol().builtin.discovery_config;
  d.discoveryProtocol = eprosima::fastrtps::rtps::DiscoveryProtocol_t::SERVER;
  d.leaseDuration = eprosima::fastrtps::c_TimeInfinite;
  d.leaseDuration_announcementperiod = eprosima::fastrtps::Duration_t(period_ms / 1000.0);
  rtps::get_server_client_default_guidPrefix(0, q.wire_protocol().prefix);
  q.wire_protocol().builtin.metatrafficUnicastLocatorList.push_back(loopback(port));
  if (dds::DomainParticipantFactory::get_instance()->create_participant(domain, q) == nullptr)
    std::_Exit(3);
  for (;;) pause();
}

[[noreturn]] void project_server(std::uint32_t domain, std::uint16_t port) {
  try {
    qswarm::DiscoveryServer server(domain, "127.0.0.1", port, kServerId);
    for (;;) pause();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ds_abort_stress: %s\n", e.what());
    std::_Exit(3);
  }
}

[[noreturn]] void clients(std::uint32_t domain, std::uint16_t port, int count) {
  auto* factory = dds::DomainParticipantFactory::get_instance();
  for (;;) {
    std::vector<dds::DomainParticipant*> up;
    for (int i = 0; i < count; ++i) {
      dds::DomainParticipantQos q;
      q.transport().use_builtin_transports = false;
      auto udp = std::make_shared<rtps::UDPv4TransportDescriptor>();
      udp->interfaceWhiteList.push_back("127.0.0.1");
      q.transport().user_transports.push_back(udp);
      q.wire_protocol().builtin.use_WriterLivelinessProtocol = false;
      auto& d = q.wire_protocol().builtin.discovery_config;
      d.discoveryProtocol = eprosima::fastrtps::rtps::DiscoveryProtocol_t::CLIENT;
      d.leaseDuration = eprosima::fastrtps::c_TimeInfinite;
      rtps::RemoteServerAttributes s;
      rtps::get_server_client_default_guidPrefix(0, s.guidPrefix);
      s.metatrafficUnicastLocatorList.push_back(loopback(port));
      d.m_DiscoveryServers.push_back(s);
      if (auto* p = factory->create_participant(domain, q)) up.push_back(p);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    for (auto* p : up) factory->delete_participant(p);
  }
}

[[noreturn]] void busy() {
  std::atomic<unsigned long> spin{0};
  for (;;) spin.fetch_add(1, std::memory_order_relaxed);
}

pid_t spawn(int nice_value, const std::function<void()>& body) {
  const pid_t pid = fork();
  if (pid < 0) {
    std::perror("fork");
    std::exit(2);
  }
  if (pid == 0) {
    setpriority(PRIO_PROCESS, 0, nice_value);
    body();
    std::_Exit(0);
  }
  return pid;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(
        stderr, "usage: ds_abort_stress project|PERIOD_MS [SECONDS=30] [CLIENTS=30] [DOMAIN=21]\n");
    return 2;
  }
  const std::string mode = argv[1];
  const double seconds = argc > 2 ? std::atof(argv[2]) : 30.0;
  const int count = argc > 3 ? std::atoi(argv[3]) : 30;
  const auto domain = static_cast<std::uint32_t>(argc > 4 ? std::atoi(argv[4]) : 21);
  const double period_ms = mode == "project" ? 0.0 : std::atof(mode.c_str());
  if (seconds <= 0 || count <= 0 || domain > qswarm::PortPlan::kMaxDomain ||
      (mode != "project" && !(period_ms > 0))) {
    std::fprintf(stderr, "ds_abort_stress: bad arguments\n");
    return 2;
  }
  const auto port = static_cast<std::uint16_t>(qswarm::PortPlan::discovery_port(domain, kServerId));
  const pid_t server = spawn(10, [&] {
    if (mode == "project") project_server(domain, port);
    timed_server(domain, port, period_ms);
  });
  std::this_thread::sleep_for(std::chrono::seconds(1));
  std::vector<pid_t> others;
  for (int i = 0; i < 2; ++i) others.push_back(spawn(0, busy));
  for (int i = 0; i < 2; ++i) others.push_back(spawn(0, [&] { clients(domain, port, count); }));

  const auto start = std::chrono::steady_clock::now();
  int status = 0;
  pid_t ended = 0;
  while (ended == 0 &&
         std::chrono::steady_clock::now() - start < std::chrono::duration<double>(seconds)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    ended = waitpid(server, &status, WNOHANG);
  }
  const double ran =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (pid_t pid : others) kill(pid, SIGKILL);
  for (pid_t pid : others) waitpid(pid, nullptr, 0);
  const std::string what =
      mode == "project" ? "the project's server" : "a server announcing every " + mode + " ms";
  if (ended == 0) {
    kill(server, SIGKILL);
    waitpid(server, nullptr, 0);
    std::printf("ds_abort_stress: %s lived through %.0f s of clients\n", what.c_str(), ran);
    return 0;
  }
  if (WIFSIGNALED(status))
    std::printf("ds_abort_stress: %s died after %.1f s: signal %d (%s)\n", what.c_str(), ran,
                WTERMSIG(status), strsignal(WTERMSIG(status)));
  else
    std::printf("ds_abort_stress: %s exited %d after %.1f s\n", what.c_str(), WEXITSTATUS(status),
                ran);
  return 1;
}
