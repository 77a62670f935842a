// plan_run: every threshold that depends on a run's size, its security or its hosts, in one place.
// docs/run-plan.md has a row for each constant below: its value, why, and where it was measured.
#include "common/scenario/run_plan.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>

#include "common/scenario/scenario.hpp"
#include "common/transport/dds_names.hpp"
#include "common/transport/port_plan.hpp"

namespace qswarm {

namespace {

// Who hears whom: up to this many agents everyone hears everyone (it costs nothing there, and the
// start barrier then waits for every agent, so all start together as the paper's runs do).
constexpr std::size_t kAllToAllUpTo = 8;
// Plain swarms of more agents discover through the run's own Discovery Server: each agent then
// discovers only the agents it may hear, where simple discovery matches every pair.
constexpr std::size_t kSimpleDiscoveryUpTo = 32;
// Through a server, past this many agents cells are partitions of region topics: one shared topic
// would introduce everyone to everyone (256 agents took 159 s to discover on it).
constexpr std::size_t kRegionTopicsAbove = 128;
// A keyed reader holds at least this many agents (and 16 more than the swarm: strangers' keys are
// filtered before they take a slot, but a restarting agent's old instance may linger).
constexpr int kMinReaderAgents = 16;

// A participant announces itself every second up to this many processes, then slower with the
// swarm (everyone hears every announcement: N^2 per period; 10 s at 256).
constexpr double kAnnouncingParticipantsPerS = 25.0;
// How long a process waits for its peer hosts' names: a compose swarm of a few dozen replicas
// starting on two cores.
constexpr double kPeerHostsWaitS = 120.0;
// Fast DDS's threads run this much nicer than an agent's tick, which is the process's deadline
// (samples wait in their sockets, where the newest wins anyway). Not under DDS-Security: its
// handshakes race between receive threads in Fast DDS 2.9.1 (docs/fast-dds-workarounds.md, W2), and
// slowed down a secure compose swarm lost a pair of replicas that never heard each other.
constexpr int kDdsThreadsNice = 15;
// The run's own Discovery Server runs at this nice value where the host lets it (root, or
// CAP_SYS_NICE): starved of CPU it batches more changes and hangs more in Fast DDS 2.9.1 (W5; on
// the 64-agent lattice beside a busy loop 7 of 40 runs hung at nice 0, 0 of 12 at -10).
constexpr int kServerNice = -10;
// Up to kTwoServersUpTo agents the run starts two Discovery Servers of its own, and every
// participant is told both: a server that hangs (W5) or dies leaves the other relaying, so peers
// that meet after it still meet. Every client hears every announcement from both, which slowed
// discovery 1.7 times at 128; at 256 in the grid discovery through two never finished within the
// start timeout (75 of 256 agents joined, none heard a peer ready), through one 250 joined.
constexpr std::size_t kTwoServersUpTo = 128;
// Up to this many agents the supervisor's Fast DDS threads, which take the records, run at
// kSupervisorThreadsNice where the host lets it, ahead of the agents' ticks: at 32 all-to-all its
// record age p99 halved, no tick was late. Not past it, where its load grows with the swarm: at
// nice -10 it made the 128-agent grid 2.3 and 3.3 % late against 0.4 and 0.7 %. Not when secure,
// whose handshakes race between receive threads (W2).
constexpr std::size_t kSupervisorAheadUpTo = 32;
constexpr int kSupervisorThreadsNice = -10;

// Past this many agents every second one by id ticks half a period after the others: two bursts
// of half the size on two cores instead of one.
constexpr std::size_t kTickPhasesAbove = 16;
// Receive at the tick up to this many agents: 0.56 to 0.65 times the CPU at 8 and 32 all-to-all,
// and discovery at the tick's priority: at 128 a ring's agents on Fast DDS's receive threads (nice
// 15) never matched a neighbour's endpoint before their start timeout, and the grid at 25 Hz ran
// 2.9 % late, unconverged, where at the tick it converged 0.9 % late. Past it the tick's drain,
// run at the tick's priority, made a swarm beyond its host later still (256 in the grid at time
// scale 0.5: 33 % late against 2 %), where nicer threads wait for idle time.
constexpr std::size_t kTickReceiveUpTo = 128;
// The record: 10 Hz per agent up to 128 agents, then this many samples per second over the
// agents (5 Hz at 256), so that the one supervisor's share of the traffic stays bounded.
constexpr double kRecordHz = 10.0;
constexpr double kRecordSamplesPerS = 1280.0;
// Past this many agents records are spread over the record period's ticks by id: a record from
// every agent on one tick lost the recorder a fifth to a third of them at 256.
constexpr std::size_t kSpreadRecordsAbove = 64;
// The supervisor keeps a silent agent present for at least this many record periods, so that a
// record rate lowered for a large swarm does not make two lost records a departure.
constexpr double kPresenceRecordPeriods = 3.0;

// The start barrier: every waiting agent announces to every other (N^2 samples per period). A
// ready agent announces and looks every 5 ms per 8 agents; a waiting one says it is here every
// 50 ms per 8 agents past 8 (at 5 ms, 32 containers saturated two cores).
constexpr double kReadyPeriodPer8S = 0.005;
constexpr double kWaitingPeriodPer8S = 0.05;
// DDS-Security signs and encrypts every sample (several times the CPU of a plain one): at 5 ms
// the announcements of 8 agents took the CPU the handshakes needed.
constexpr double kSecureBarrierSlowdown = 10.0;
// An agent starts anyway after 30 s plus half a second per agent at its barrier: discovery grows
// with the swarm (100 agents on 2 cores took 25 s). A late joiner waits 10 s more.
constexpr double kStartTimeoutS = 30.0;
constexpr double kStartTimeoutPerAgentS = 0.5;
constexpr double kJoinAfterStartS = 10.0;
// An agent stops after twice the duration plus 30 s of flight; `swarm run` after the duration and
// room for the start: never less than 120 s, nor than the agents' own start timeout and 30 s.
constexpr double kLauncherMinStartRoomS = 120.0;

// Replicas claiming ids: a claim every 0.1 s per 6 replicas, a claim given up after 60 s plus 4 s
// per replica, and room for twice the swarm's claims (duplicates, restarts) and 16 more.
constexpr double kClaimPeriodPer6S = 0.1;
constexpr double kClaimTimeoutS = 60.0;
constexpr double kClaimTimeoutPerReplicaS = 4.0;

[[noreturn]] void refuse(const std::string& what) { throw ScenarioError(what); }

DiscoveryMode discovery_of(const RunConfig& rc, const Hosts& h, bool secure) {
  if (h.peer_hosts) {
    if (!h.discovery_server.empty())
      refuse(
          "--peer-hosts (QSWARM_PEER_HOSTS) and --discovery-server (QSWARM_DISCOVERY_SERVER): "
          "discovery by unicast to the peers, or through the server, not both");
    return DiscoveryMode::kPeerHosts;
  }
  if (secure && !h.discovery_server.empty())
    refuse(
        "--discovery-server (QSWARM_DISCOVERY_SERVER): a secure run cannot discover through a "
        "Discovery Server (Fast DDS 2.9 has no secure one)");
  if (secure && rc.transport.discovery == Discovery::kServer)
    refuse(
        "scenario field 'transport.discovery': expected SIMPLE with a keystore (Fast DDS 2.9 has "
        "no secure Discovery Server), got SERVER");
  if (h.unicast_block && !h.discovery_server.empty())
    refuse(
        "--unicast-peers and --discovery-server (QSWARM_DISCOVERY_SERVER): discovery by unicast "
        "to a block, or through the server, not both");
  if (!h.discovery_server.empty()) return DiscoveryMode::kServer;
  if (h.unicast_block) return DiscoveryMode::kUnicastBlock;
  if (!h.launcher) return DiscoveryMode::kMulticast;
  // A secure run on one host discovers by unicast within its block: Fast DDS 2.9.1 can leave a
  // secure pair unpaired when multicast and unicast discovery are handled at once
  // (docs/fast-dds-workarounds.md, W2). Not in a container, where the block has no one address.
  if (secure) return h.interface.empty() ? DiscoveryMode::kMulticast : DiscoveryMode::kUnicastBlock;
  const bool server = rc.transport.discovery ? *rc.transport.discovery == Discovery::kServer
                                             : rc.agents.size() > kSimpleDiscoveryUpTo;
  return server ? DiscoveryMode::kServer : DiscoveryMode::kMulticast;
}

}  // namespace

const char* to_string(Delivery d) {
  switch (d) {
    case Delivery::kAll:
      return "all";
    case Delivery::kReach:
      return "reach";
    case Delivery::kNeighbours:
      break;
  }
  return "neighbours";
}

const char* to_string(DiscoveryMode d) {
  switch (d) {
    case DiscoveryMode::kUnicastBlock:
      return "unicast-block";
    case DiscoveryMode::kPeerHosts:
      return "peer-hosts";
    case DiscoveryMode::kServer:
      return "server";
    case DiscoveryMode::kMulticast:
      break;
  }
  return "multicast";
}

double RunPlan::tick_phase(const std::set<AgentId>& ids, AgentId id) const {
  const auto it = ids.find(id);
  if (tick_phases < 2 || it == ids.end()) return 0.0;
  return std::distance(ids.begin(), it) % 2 == 1 ? 0.5 : 0.0;
}

RunPlan plan_run(const RunConfig& rc, const Hosts& hosts) {
  RunPlan p;
  const std::size_t n = rc.agents.size();
  const double size = static_cast<double>(n);
  p.agents = n;
  p.secure = !rc.transport.keystore.empty();
  p.hosts = hosts;

  p.delivery = rc.transport.delivery
                   ? *rc.transport.delivery
                   : (n <= kAllToAllUpTo ? Delivery::kAll : Delivery::kNeighbours);
  p.discovery = discovery_of(rc, hosts, p.secure);
  p.own_server = p.discovery == DiscoveryMode::kServer && hosts.discovery_server.empty();
  p.routing = p.discovery != DiscoveryMode::kServer ? Routing::kPartitions
              : n > kRegionTopicsAbove              ? Routing::kRegionTopics
                                                    : Routing::kNamedTopics;
  // One datagram per sample to the run's group where everyone hears everyone on loopback. Not
  // where the test transport drops (its losses would hit every reader of a sample at once), nor
  // with discovery by unicast (no multicast is sent or heard there), nor over shared memory, nor
  // off loopback (containers' networks carry multicast unreliably), nor where the scenario says.
  const bool unicast =
      p.discovery == DiscoveryMode::kUnicastBlock || p.discovery == DiscoveryMode::kPeerHosts;
  if (rc.transport.multicast && p.delivery == Delivery::kAll &&
      hosts.interface.rfind("127.", 0) == 0 && rc.faults.transport_drop_percent == 0 && !unicast &&
      !p.secure && !rc.transport.shared_memory)
    p.multicast_group = state_multicast_group(rc.transport.run_id);
  p.reader_agents = std::max(static_cast<int>(n), kMinReaderAgents);

  p.own_servers = !p.own_server ? 0 : n <= kTwoServersUpTo ? 2 : 1;
  p.participants = static_cast<int>(n) + 1 + p.own_servers;
  p.participant_announce_period_s = std::max(1.0, size / kAnnouncingParticipantsPerS);
  p.peer_hosts_wait_s = hosts.peer_hosts ? kPeerHostsWaitS : 0.0;
  if (hosts.peer_hosts)
    p.peer_host_addresses =
        hosts.unicast_block ? hosts.peer_host_names : static_cast<std::size_t>(p.participants);
  p.dds_threads_nice = p.secure ? 0 : kDdsThreadsNice;
  p.server_nice = p.own_server ? kServerNice : 0;
  p.supervisor_threads_nice = !p.secure && n <= kSupervisorAheadUpTo ? kSupervisorThreadsNice : 0;

  p.tick_phases = n > kTickPhasesAbove ? 2 : 1;
  p.tick_receive = rc.transport.tick_receive ? *rc.transport.tick_receive : n <= kTickReceiveUpTo;
  const double asked_hz =
      rc.judge.record_hz ? *rc.judge.record_hz : std::min(kRecordHz, kRecordSamplesPerS / size);
  // Whole samples: the rate is the consensus rate over a whole number.
  p.record_every = static_cast<std::uint32_t>(
      std::max(1L, std::lround(rc.agent.consensus_hz / std::max(asked_hz, 1e-9))));
  p.record_hz = rc.agent.consensus_hz / static_cast<double>(p.record_every);
  p.spread_records = n > kSpreadRecordsAbove;
  p.presence_timeout_s =
      std::max(rc.agent.neighbor_timeout_s, kPresenceRecordPeriods / p.record_hz);

  const double per8 = std::max(1.0, size / 8.0);
  p.barrier_announce_period_s = kReadyPeriodPer8S * per8;
  p.barrier_waiting_period_s =
      n <= kAllToAllUpTo ? p.barrier_announce_period_s : kWaitingPeriodPer8S * size / 8.0;
  if (p.secure) {
    p.barrier_announce_period_s *= kSecureBarrierSlowdown;
    p.barrier_waiting_period_s *= kSecureBarrierSlowdown;
  }
  // The supervisor hears an agent at its barrier only through these announcements: one at least
  // every half of its presence timeout, or it would count the agent departed between two.
  p.barrier_waiting_period_s =
      std::min(p.barrier_waiting_period_s, 0.5 * p.presence_timeout_s / hosts.time_scale);
  p.barrier_announce_period_s = std::min(p.barrier_announce_period_s, p.barrier_waiting_period_s);
  p.start_timeout_s = kStartTimeoutS + kStartTimeoutPerAgentS * size;
  p.join_timeout_s = p.start_timeout_s + kJoinAfterStartS;
  const double flight_s = rc.judge.duration_s / hosts.time_scale;
  p.agent_wall_limit_s = 2.0 * flight_s + 30.0;
  p.launcher_wall_limit_s = flight_s + std::max(kLauncherMinStartRoomS, p.start_timeout_s + 30.0);

  p.claim_period_s = kClaimPeriodPer6S * std::max(1.0, size / 6.0);
  p.claim_timeout_s = kClaimTimeoutS + kClaimTimeoutPerReplicaS * size;
  p.claim_capacity = 2 * n + 16;

  p.run_partition = dds_names::run_partition(rc.transport.run_id);
  p.record_partition = dds_names::record_partition(rc.transport.run_id);
  return p;
}

RunPlan plan_at(const RunConfig& rc, double time_scale) {
  if (rc.plan.hosts.time_scale == time_scale) return rc.plan;
  Hosts hosts = rc.plan.hosts;
  hosts.time_scale = time_scale;
  return plan_run(rc, hosts);
}

void replan(RunConfig& rc, const Hosts& hosts) {
  rc.plan = plan_run(rc, hosts);
  scenario::Transport& t = *rc.resolved.mutable_transport();
  t.set_delivery(rc.plan.delivery == Delivery::kAll     ? scenario::Transport::ALL
                 : rc.plan.delivery == Delivery::kReach ? scenario::Transport::REACH
                                                        : scenario::Transport::NEIGHBOURS);
  t.set_discovery(rc.plan.discovery == DiscoveryMode::kServer ? scenario::Transport::SERVER
                                                              : scenario::Transport::SIMPLE);
  t.set_receive(rc.plan.tick_receive ? scenario::Transport::TICK : scenario::Transport::THREADS);
  rc.resolved.mutable_record()->set_rate_hz(rc.plan.record_hz);
}

plan::RunPlan to_proto(const RunPlan& p, int participant_base) {
  plan::RunPlan o;
  o.set_agents(static_cast<std::uint32_t>(p.agents));
  o.set_secure(p.secure);
  plan::Hosts& h = *o.mutable_hosts();
  h.set_launcher(p.hosts.launcher);
  h.set_interface(p.hosts.interface);
  h.set_discovery_server(p.hosts.discovery_server);
  h.set_peer_hosts(p.hosts.peer_hosts);
  if (p.hosts.unicast_block) {
    h.set_unicast_block_first(p.hosts.unicast_block->first);
    h.set_unicast_block_count(p.hosts.unicast_block->second);
  }
  h.set_time_scale(p.hosts.time_scale);
  o.set_delivery(to_string(p.delivery));
  o.set_routing(to_string(p.routing));
  o.set_multicast_group(p.multicast_group);
  o.set_reader_agents(p.reader_agents);
  o.set_tick_receive(p.tick_receive);
  o.set_discovery(to_string(p.discovery));
  o.set_own_server(p.own_server);
  o.set_own_servers(p.own_servers);
  o.set_participants(p.participants);
  o.set_participant_announce_period_s(p.participant_announce_period_s);
  o.set_peer_hosts_wait_s(p.peer_hosts_wait_s);
  o.set_peer_host_addresses(static_cast<std::uint32_t>(p.peer_host_addresses));
  o.set_dds_threads_nice(p.dds_threads_nice);
  o.set_server_nice(p.server_nice);
  o.set_supervisor_threads_nice(p.supervisor_threads_nice);
  o.set_tick_phases(p.tick_phases);
  o.set_record_hz(p.record_hz);
  o.set_record_every(p.record_every);
  o.set_spread_records(p.spread_records);
  o.set_presence_timeout_s(p.presence_timeout_s);
  o.set_barrier_announce_period_s(p.barrier_announce_period_s);
  o.set_barrier_waiting_period_s(p.barrier_waiting_period_s);
  o.set_start_timeout_s(p.start_timeout_s);
  o.set_join_timeout_s(p.join_timeout_s);
  o.set_agent_wall_limit_s(p.agent_wall_limit_s);
  o.set_launcher_wall_limit_s(p.launcher_wall_limit_s);
  o.set_claim_period_s(p.claim_period_s);
  o.set_claim_timeout_s(p.claim_timeout_s);
  o.set_claim_capacity(p.claim_capacity);
  o.set_state_topic(dds_names::kStateTopic);
  o.set_record_topic(dds_names::kRecordTopic);
  o.set_claim_topic(dds_names::kClaimTopic);
  o.set_run_partition(p.run_partition);
  o.set_record_partition(p.record_partition);
  o.set_participant_base(participant_base);
  return o;
}

}  // namespace qswarm
