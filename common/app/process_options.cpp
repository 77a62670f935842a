#include "common/app/process_options.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cctype>
#include <cstdio>

#include "common/app/cli_checks.hpp"
#include "common/dds/participant.hpp"
#include "common/transport/port_plan.hpp"

namespace qswarm {

void add_process_options(CLI::App& app, ProcessOptions& o) {
  app.add_option("--scenario", o.scenario, "scenario file (Protobuf text format)")->required();
  app.add_option("--time-scale", o.time_scale, "simulated seconds per wall second")
      ->check(finite_range(0.01, 100.0));
  app.add_option("--domain", o.domain, "DDS domain id (overrides the scenario)")
      ->check(CLI::Range(0, static_cast<int>(PortPlan::kMaxDomain)));
  app.add_option("--interface", o.interface,
                 "IPv4 address DDS binds to (overrides the scenario; \"any\": every interface, "
                 "as inside a container)");
  app.add_option("--agents", o.agents,
                 "fly N seeded random agents instead of the scenario's list (compose: the swarm's "
                 "size)")
      ->envname("QSWARM_AGENTS")
      ->check(CLI::Range(1, static_cast<int>(kMaxSwarmAgents)));
  app.add_option("--discovery-server", o.discovery_server,
                 "discover through the Fast DDS Discovery Server at HOST:PORT (containers, hosts "
                 "without multicast), or the servers HOST:PORT,HOST:PORT (swarm-discovery "
                 "--servers, listed alike everywhere); \"none\" or empty: simple discovery")
      ->envname("QSWARM_DISCOVERY_SERVER")
      ->transform([](const std::string& v) { return v == "none" ? std::string() : v; });
  app.add_option("--participant-id", o.participant_id,
                 "DDS participant id in the port plan (swarm run gives each process its own)")
      ->check(CLI::Range(0, PortPlan::kMaxParticipantId));
  app.add_option("--unicast-peers", o.unicast_peers,
                 "FIRST:COUNT: discover only these participant ids of the port plan, by unicast "
                 "(swarm run gives a secure run's processes its block)")
      ->check([](const std::string& v) {
        std::string why;
        return parse_unicast_peers(v, why) ? std::string() : why;
      });
  app.add_option("--peer-hosts", o.peer_hosts,
                 "NAME,...: discover by unicast the one participant at each address of these "
                 "names (secure compose: agent,supervisor)")
      ->envname("QSWARM_PEER_HOSTS")
      ->check([](const std::string& v) {
        for (const std::string& name : split_names(v)) {
          // A host name or a dotted IPv4 address: letters, digits, '-' and '.', no port.
          const bool host =
              !name.empty() && name.front() != '-' && name.front() != '.' &&
              std::all_of(name.begin(), name.end(), [](char c) {
                return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '-' || c == '.';
              });
          if (!host) {
            std::string why = "\"";
            why += name;
            why += "\" in \"";
            why += v;
            why += "\" is not a host name or an IPv4 address (NAME,NAME,... with no port)";
            return why;
          }
        }
        return std::string();
      });
  app.add_option("--seed", o.seed, "run seed (overrides the scenario)")
      ->check(CLI::Range(std::int64_t{0}, std::int64_t{4294967295}));
  app.add_option("--keystore", o.keystore,
                 "DDS-Security with this keystore (swarm keys; overrides the scenario's "
                 "transport.keystore; compose: swarm keys --compose)")
      ->envname("QSWARM_KEYSTORE");
}

Hosts hosts_of(const RunConfig& rc, const ProcessOptions& o) {
  Hosts h;
  h.launcher = false;  // the launcher's choices arrive as flags
  h.interface = o.interface.empty() ? rc.transport.interface : o.interface;
  if (h.interface == "any") h.interface.clear();
  h.discovery_server = o.discovery_server;
  h.peer_hosts = !o.peer_hosts.empty();
  h.peer_host_names = split_names(o.peer_hosts).size();
  std::string why;
  if (const auto block = parse_unicast_peers(o.unicast_peers, why)) h.unicast_block = *block;
  h.time_scale = o.time_scale;
  return h;
}

std::optional<RunConfig> load_for_process(const char* prog, const ProcessOptions& opts) {
  try {
    ScenarioOverrides o;
    o.domain_id = opts.domain;
    o.seed = opts.seed;
    o.agents = opts.agents;
    o.keystore = opts.keystore;
    RunConfig rc = load_scenario(opts.scenario, o);
    replan(rc, hosts_of(rc, opts));
    // Checked (and resolved, with retries while a container network's DNS catches up) before
    // anything is created, so that a bad address is bad input: exit 2.
    if (!opts.discovery_server.empty()) resolve_discovery_servers(opts.discovery_server);
    const std::string problem =
        interface_problem(opts.interface.empty() ? rc.transport.interface : opts.interface);
    if (!problem.empty()) {
      std::fprintf(stderr, "%s: %s: %s\n", prog,
                   opts.interface.empty() ? "scenario field 'transport.interface'" : "--interface",
                   problem.c_str());
      return std::nullopt;
    }
    return rc;
  } catch (const ScenarioError& e) {
    std::fprintf(stderr, "%s: %s\n", prog, e.what());
    return std::nullopt;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "%s: --discovery-server (QSWARM_DISCOVERY_SERVER): %s\n", prog, e.what());
    return std::nullopt;
  }
}

}  // namespace qswarm
