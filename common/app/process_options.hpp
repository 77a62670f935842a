#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/scenario/scenario.hpp"
#include "common/transport/name_list.hpp"

namespace CLI {
class App;
}

namespace qswarm {

// The flags `swarm run` passes to swarm-agent and swarm-supervisor, declared once so that they
// mean the same, and the run they load.
struct ProcessOptions {
  std::string scenario;          // --scenario (required)
  double time_scale = 1.0;       // --time-scale
  int domain = -1;               // --domain (overrides the scenario)
  std::int64_t seed = -1;        // --seed (overrides the scenario)
  std::string interface;         // --interface (overrides the scenario; "any": every interface)
  int agents = -1;               // --agents / QSWARM_AGENTS: N seeded random agents (compose)
  std::string discovery_server;  // --discovery-server / QSWARM_DISCOVERY_SERVER: HOST:PORT
  int participant_id = -1;       // --participant-id: its place in the port plan (-1: Fast DDS's)
  std::string keystore;          // --keystore / QSWARM_KEYSTORE (overrides the scenario)
  // --unicast-peers FIRST:COUNT: discover only the participant ids FIRST.. of the port plan, by
  // unicast (ParticipantOptions::unicast_peers_*); swarm run passes its block to a secure run.
  std::string unicast_peers;
  // --peer-hosts / QSWARM_PEER_HOSTS NAME,...: the unicast peers are at every address of these
  // names (compose services: each replica of one), one participant per host, so that port plan id
  // 0 and peers 0:1 go with it unless given (process_dds finds them).
  std::string peer_hosts;
};
void add_process_options(CLI::App& app, ProcessOptions& o);

// The hosts a process started alone sees from its flags (the launcher's choices arrive as flags:
// --participant-id, --unicast-peers, --discovery-server).
Hosts hosts_of(const RunConfig& rc, const ProcessOptions& o);

// Loads the scenario with the process's --domain/--seed overrides and plans it for the hosts its
// flags say (rc.plan); on bad input prints "PROG: message" to stderr and returns nothing (the
// caller exits 2).
std::optional<RunConfig> load_for_process(const char* prog, const ProcessOptions& o);

}  // namespace qswarm
