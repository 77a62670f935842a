// swarm-discovery: a Fast DDS Discovery Server that a swarm's participants find each other through:
// the compose swarm's (docker/docker-compose.yml) and a large local run's (`swarm run` starts one
// for transport.discovery SERVER). Runs until SIGINT/SIGTERM.
#include <CLI/CLI.hpp>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <unistd.h>

#include "common/dds/discovery_server.hpp"
#include "common/dds/participant.hpp"
#include "common/transport/port_plan.hpp"

namespace {
std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"swarm-discovery: a Fast DDS Discovery Server for the compose swarm"};
  std::string listen;
  unsigned port = 11811;
  unsigned domain = 0;
  int participant_id = -1;
  std::string servers;
  int index = 0;
  auto* listen_opt = app.add_option(
      "--listen", listen, "IPv4 address or host name to listen on (default: this host's name)");
  auto* port_opt = app.add_option("--port", port, "UDP port")->check(CLI::Range(1, 65535));
  auto* servers_opt =
      app.add_option("--servers", servers,
                     "HOST:PORT,HOST:PORT: the swarm's servers, listed as its processes' "
                     "--discovery-server lists them; this one is the entry at --index, and knows "
                     "the others")
          ->excludes(listen_opt)
          ->excludes(port_opt);
  app.add_option("--index", index, "this server's place in --servers, from 0")
      ->check(CLI::Range(0, static_cast<int>(qswarm::kMaxDiscoveryServers) - 1))
      ->needs(servers_opt);
  app.add_option("--domain", domain, "DDS domain id")
      ->check(CLI::Range(0, static_cast<int>(qswarm::PortPlan::kMaxDomain)));
  std::string ready_file;
  app.add_option("--ready-file", ready_file,
                 "a file to create once it listens (swarm run waits for it)");
  app.add_option("--participant-id", participant_id,
                 "its participant id in the port plan (swarm run's own server; its ports are "
                 "taken exactly, a taken one is an error)")
      ->check(CLI::Range(0, 544));
  int nice = 0;
  app.add_option("--nice", nice,
                 "run this much nicer than started (negative: a higher priority, where the host "
                 "allows it; otherwise it says so and runs as started)")
      ->check(CLI::Range(-20, 19));
  bool hang = false;
  app.add_flag("--test-hang", hang,
               "(tests) stop (SIGSTOP) once it listens: a hung server, which relays nothing and "
               "ignores SIGTERM")
      ->group("");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  std::vector<std::pair<std::string, std::uint16_t>> list;
  if (!servers.empty()) {
    try {
      list = qswarm::resolve_discovery_servers(servers);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "swarm-discovery: --servers: %s\n", e.what());
      return 2;
    }
    if (index >= static_cast<int>(list.size())) {
      std::fprintf(stderr, "swarm-discovery: --index %d: --servers lists %zu servers\n", index,
                   list.size());
      return 2;
    }
    listen = list[index].first;
    port = list[index].second;
  }
  if (listen.empty()) {
    char host[256] = {};
    gethostname(host, sizeof host - 1);
    listen = host;
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  // Before the participant exists, so that every thread Fast DDS starts inherits it.
  if (nice != 0) std::printf("swarm-discovery: %s\n", qswarm::change_thread_nice(nice).c_str());
  try {
    qswarm::DiscoveryServer server(domain, listen, static_cast<std::uint16_t>(port), participant_id,
                                   index, list);
    std::printf("swarm-discovery: serving domain %u on %s:%u\n", domain, server.address().c_str(),
                port);
    std::fflush(stdout);
    if (!ready_file.empty() && !std::ofstream(ready_file)) {
      std::fprintf(stderr, "swarm-discovery: cannot write %s\n", ready_file.c_str());
      return 1;
    }
    if (hang) {
      std::printf("swarm-discovery: hanging (--test-hang)\n");
      std::fflush(stdout);
      std::raise(SIGSTOP);
    }
    int last = -1;
    while (!g_stop) {
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      if (server.clients() != last) {
        last = server.clients();
        std::printf("swarm-discovery: %d participants\n", last);
        std::fflush(stdout);
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "swarm-discovery: %s\n", e.what());
    return 2;
  }
  return 0;
}
