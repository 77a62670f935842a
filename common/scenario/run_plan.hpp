#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <utility>

#include "common/core/agent.hpp"
#include "common/transport/routing.hpp"
#include "proto/plan.pb.h"

namespace qswarm {

struct RunConfig;

// Which samples an agent is sent: those of the agents that can be its neighbours, everyone's, or
// (experimental) only those within its reach.
enum class Delivery { kNeighbours, kAll, kReach };
// How a run's participants discover each other, as the scenario may ask (Transport.Discovery).
enum class Discovery { kSimple, kServer };

// How each participant finds the others.
enum class DiscoveryMode {
  kMulticast,     // Fast DDS's simple discovery, announced to the domain's multicast group
  kUnicastBlock,  // by unicast alone, to the run's block of participant ids on one host
  kPeerHosts,     // by unicast alone, to the one participant at each address of named hosts
  kServer,        // through a Fast DDS Discovery Server (the run's own, or one given)
};

const char* to_string(Delivery d);
const char* to_string(DiscoveryMode d);

// Where a run's processes are, beyond what the scenario says: what plan_run needs of the hosts.
struct Hosts {
  // `swarm run` on one host: it reserves a block of participant ids for the run and starts the
  // run's own Discovery Server when the plan discovers through one. False: a process started
  // alone (a compose replica, a pod), which discovers as its flags say.
  bool launcher = true;
  std::string interface = "127.0.0.1";  // where DDS binds ("": every interface, a container)
  std::string discovery_server;         // HOST:PORT of a server given to the process
  bool peer_hosts = false;              // --peer-hosts: one participant per host, found by name
  std::size_t peer_host_names = 0;      // how many names --peer-hosts lists
  // An explicit block of participant ids to discover by unicast (--unicast-peers FIRST:COUNT).
  std::optional<std::pair<int, int>> unicast_block;
  double time_scale = 1.0;  // simulated seconds per wall second
};

// Every decision a run makes because of its size, its security or its hosts, made once by
// plan_run. `swarm inspect` prints it, the run directory keeps it (plan.txtpb), and the launcher,
// the agents and the supervisor read it instead of deriving a rule of their own. Each threshold
// has its row, its reason and where it was measured in docs/run-plan.md.
struct RunPlan {
  // What it was made from.
  std::size_t agents = 0;
  bool secure = false;
  Hosts hosts;

  // Who hears whom, and how.
  Delivery delivery = Delivery::kAll;
  Routing routing = Routing::kPartitions;
  // The group a state reader listens on where every agent hears every agent on loopback: one
  // datagram per sample instead of one per reader ("": unicast).
  std::string multicast_group;
  // A state reader's room: agents the keyed reader holds (Fast DDS defaults to 10).
  int reader_agents = 0;
  // An agent reads its sockets at its tick (TickReceive), not with Fast DDS's receive threads.
  bool tick_receive = true;

  // Discovery and ports.
  DiscoveryMode discovery = DiscoveryMode::kMulticast;
  bool own_server = false;  // the launcher starts the run's Discovery Servers (swarm-discovery)
  int own_servers = 0;      // how many: each participant is told them all, in one order
  // Participants of the run on the port plan: the supervisor, the agents and its own servers.
  int participants = 0;
  double participant_announce_period_s = 1.0;  // wall: a participant's announcements
  double peer_hosts_wait_s = 0.0;              // wall: how long a process waits for peer names
  // The addresses it waits for: one per participant (one per container, found by service name),
  // or, with a block of ids per host (--unicast-peers), one per name (each a host).
  std::size_t peer_host_addresses = 0;
  int dds_threads_nice = 0;  // how much nicer an agent's Fast DDS threads run than its tick
  int server_nice = 0;  // how much nicer than the launcher its servers run (-10: higher priority)
  int supervisor_threads_nice = 0;  // the same for the supervisor's Fast DDS threads

  // Ticks and the record.
  int tick_phases = 1;      // 2: every second agent by id ticks half a period after the others
  double record_hz = 10.0;  // samples per second per agent to the supervisor
  std::uint32_t record_every = 1;   // every how many ticks an agent records
  bool spread_records = false;      // records spread over those ticks by id, not one tick for all
  double presence_timeout_s = 1.0;  // swarm seconds the supervisor keeps a silent agent present

  // The start and the end (wall seconds).
  double barrier_announce_period_s = 0.005;  // a ready agent's announcements, and its polls
  double barrier_waiting_period_s = 0.005;   // a waiting agent's beacon
  double start_timeout_s = 30.0;       // an agent starts anyway after this long at its barrier
  double join_timeout_s = 40.0;        // a late joiner joins anyway after this long waiting
  double agent_wall_limit_s = 0.0;     // an agent stops after flying this long
  double launcher_wall_limit_s = 0.0;  // `swarm run` stops everything after this long

  // Compose replicas claiming their ids (IdClaimer).
  double claim_period_s = 0.1;
  double claim_timeout_s = 60.0;
  std::size_t claim_capacity = 16;  // replicas' claims kept

  // Names on the wire.
  std::string run_partition, record_partition;

  // The phase of agent `id` (a fraction of the tick period; 0 for an id not in `ids`).
  double tick_phase(const std::set<AgentId>& ids, AgentId id) const;
  // The participant ids of the run's processes in the block from `base` (the launcher's
  // reservation): the supervisor, the agent at `index` in the scenario's order, the servers.
  int supervisor_participant(int base) const { return base; }
  int agent_participant(int base, std::size_t index) const {
    return base + 1 + static_cast<int>(index);
  }
  int server_participant(int base, int server) const {
    return base + participants - own_servers + server;
  }
};

// The plan of a resolved run on these hosts: a pure function. Throws ScenarioError naming the
// field or flag when what the run asks for cannot be honoured there (a Discovery Server with a
// keystore, peer hosts beside a server).
RunPlan plan_run(const RunConfig& rc, const Hosts& hosts);
// rc.plan made anew for these hosts, its decisions written into the scenario as run.
void replan(RunConfig& rc, const Hosts& hosts);
// rc.plan on the same hosts at another time scale (its wall periods and limits follow it).
RunPlan plan_at(const RunConfig& rc, double time_scale);

// The plan as the run directory keeps it (plan.txtpb) and `swarm inspect` prints it, with the
// launcher's block of participant ids from `participant_base` (-1: none chosen).
plan::RunPlan to_proto(const RunPlan& p, int participant_base = -1);

}  // namespace qswarm
