#include "common/dds/participant.hpp"

#include "common/dds/tick_transport.hpp"
#include "common/security/keystore.hpp"
#include "common/transport/name_list.hpp"
#include "common/transport/port_plan.hpp"

#include <arpa/inet.h>
#include <fastdds/rtps/attributes/ServerAttributes.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/shared_mem/SharedMemTransportDescriptor.h>
#include <fastdds/rtps/transport/test_UDPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>
#include <netdb.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>
#include <atomic>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

namespace qswarm {

namespace dds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastdds::rtps;

namespace {
std::atomic<int> g_creating{0};
struct CreatingParticipant {
  CreatingParticipant() { ++g_creating; }
  ~CreatingParticipant() { --g_creating; }
  CreatingParticipant(const CreatingParticipant&) = delete;
  CreatingParticipant& operator=(const CreatingParticipant&) = delete;
};
}  // namespace

bool creating_participant() { return g_creating > 0; }

void disable_writer_liveliness(dds::DomainParticipantQos& qos) {
  qos.wire_protocol().builtin.use_WriterLivelinessProtocol = false;
}

DdsParticipant::DdsParticipant(const ParticipantOptions& opts) : opts_(opts) {
  dds::DomainParticipantQos pqos;
  pqos.name(opts.name);
  pqos.transport().use_builtin_transports = false;
  std::shared_ptr<rtps::TransportDescriptorInterface> udp;
  if (opts.test_drop_data_percent > 0 || opts.test_drop_writer_announcements) {
    auto t = std::make_shared<rtps::test_UDPv4TransportDescriptor>();
    if (!opts.interface.empty()) t->interfaceWhiteList.push_back(opts.interface);
    t->dropDataMessagesPercentage = opts.test_drop_data_percent;
    t->dropPublicationBuiltinTopicData = opts.test_drop_writer_announcements;
    udp = t;
  } else {
    auto u = std::make_shared<rtps::UDPv4TransportDescriptor>();
    if (!opts.interface.empty()) u->interfaceWhiteList.push_back(opts.interface);
    udp = u;
  }
  if (opts.tick_receive) {
    // Fast DDS still sends (and drops, for the test transport); the sockets it would read with a
    // thread each are read by the loop's thread.
    tick_rx_ = std::make_shared<TickReceive>(opts.interface);
    udp = tick_transport(udp, tick_rx_);
  }
  pqos.transport().user_transports.push_back(udp);
  if (opts.shared_memory) {
    pqos.transport().user_transports.push_back(
        std::make_shared<rtps::SharedMemTransportDescriptor>());
  }
  // The port plan: a block of ports per domain, room for every participant of the largest swarm.
  auto& ports = pqos.wire_protocol().port;
  ports.portBase = PortPlan::kBase;
  ports.domainIDGain = PortPlan::kDomainGain;
  ports.participantIDGain = PortPlan::kParticipantGain;
  if (opts.domain_id > PortPlan::kMaxDomain)
    throw std::invalid_argument("dds: domain " + std::to_string(opts.domain_id) +
                                " is beyond the port plan's 0.." +
                                std::to_string(PortPlan::kMaxDomain));
  // Fast DDS's own choice of ports (its id 0, then the next ports while taken) would take the ports
  // of a run's reserved ids; every participant gets an id whose ports it checks first, so that a
  // taken one is said (Fast DDS would otherwise come up without them and hear nobody).
  pqos.wire_protocol().builtin.mutation_tries = 0;
  disable_writer_liveliness(pqos);
  // Participants announce an infinite lease, so no peer ever runs a lease check on them: Fast DDS
  // 2.9.1 races a peer's lease check (timer thread) against that peer's removal when it leaves
  // (receive thread), and the check then asserts on a cleared proxy (docs/fast-dds-workarounds.md,
  // W1). The agents judge liveness themselves (the neighbour timeout);
  // a participant that leaves is still removed at once by its DISPOSE. Announcements every second
  // (not Fast DDS's 3 s: one lost while many processes start is repeated a second later), or less
  // often in a large swarm, where every participant hears every announcement.
  auto& discovery = pqos.wire_protocol().builtin.discovery_config;
  discovery.leaseDuration = eprosima::fastrtps::c_TimeInfinite;
  discovery.leaseDuration_announcementperiod =
      eprosima::fastrtps::Duration_t(std::max(1.0, opts.announce_period_s));
  if (!opts.keystore.empty()) {
    if (!opts.discovery_server.empty())
      throw std::invalid_argument(
          "dds: a secure participant cannot use a Discovery Server (Fast DDS 2.9 has no secure "
          "one)");
    auto& props = pqos.properties().properties();
    for (const auto& [name, value] : Keystore(opts.keystore).participant_properties(opts.identity))
      props.emplace_back(name, value);
  }
  if (opts.unicast_peers_count > 0) {
    if ((opts.interface.empty() && opts.unicast_peer_hosts.empty()) ||
        !opts.discovery_server.empty())
      throw std::invalid_argument(
          "dds: unicast discovery needs one interface address or peer hosts, and no Discovery "
          "Server");
    if (opts.unicast_peers_first < 0 ||
        opts.unicast_peers_first + opts.unicast_peers_count > PortPlan::kMaxParticipantId + 1)
      throw std::invalid_argument("dds: unicast peers beyond the port plan's ids 0..544");
    // Explicit unicast locators (port 0: the participant id's own ports) leave Fast DDS no
    // default multicast one; the initial peers replace the multicast announcements. Every
    // interface (0.0.0.0) where none is named: Fast DDS lists each of them in its announcements.
    eprosima::fastrtps::rtps::Locator_t own;
    eprosima::fastrtps::rtps::IPLocator::setIPv4(
        own, opts.interface.empty() ? std::string("0.0.0.0") : opts.interface);
    pqos.wire_protocol().builtin.metatrafficUnicastLocatorList.push_back(own);
    pqos.wire_protocol().default_unicast_locator_list.push_back(own);
    const std::vector<std::string> hosts = opts.unicast_peer_hosts.empty()
                                               ? std::vector<std::string>{opts.interface}
                                               : opts.unicast_peer_hosts;
    for (const std::string& host : hosts) {
      eprosima::fastrtps::rtps::Locator_t peer;
      if (!eprosima::fastrtps::rtps::IPLocator::setIPv4(peer, host))
        throw std::invalid_argument("dds: unicast peer host \"" + host +
                                    "\" is not an IPv4 address");
      for (int i = 0; i < opts.unicast_peers_count; ++i) {
        peer.port = PortPlan::discovery_port(opts.domain_id, opts.unicast_peers_first + i);
        pqos.wire_protocol().builtin.initialPeersList.push_back(peer);
      }
    }
  }
  if (!opts.discovery_server.empty()) {
    discovery.discoveryProtocol = eprosima::fastrtps::rtps::DiscoveryProtocol_t::CLIENT;
    add_discovery_servers(resolve_discovery_servers(opts.discovery_server), -1,
                          discovery.m_DiscoveryServers);
  }
  // A process given its id (the launcher's plan) takes exactly that one. One without (a lone
  // agent, a tool, a test's participant) takes one of the highest free ids, away from the blocks
  // runs reserve from 0 up, and another one if a process started at the same moment won it.
  // One participant of this process at a time takes its ports: the check below cannot tell two
  // of this process's participants apart.
  static std::mutex taking_ports;
  const std::lock_guard<std::mutex> lock(taking_ports);
  const bool given = opts.participant_id >= 0;
  int id = given ? opts.participant_id : PortPlan::kMaxParticipantId + 1;
  int skip = static_cast<int>(::getpid() % 8);  // processes started alike spread out
  for (int attempt = 0;; ++attempt) {
    if (!given) {
      // The next lower free id, passing over `skip` free ones on the first try.
      for (--id; id >= 0; --id) {
        if (!participant_ports_problem(opts.domain_id, id, opts.interface).empty()) continue;
        if (skip == 0) break;
        --skip;
      }
      if (id < 0)
        throw std::runtime_error("dds: no free participant id on domain " +
                                 std::to_string(opts.domain_id) + " (0 to 544 all taken)");
    } else if (const std::string problem =
                   participant_ports_problem(opts.domain_id, id, opts.interface);
               !problem.empty()) {
      throw std::runtime_error("dds: " + problem);
    }
    pqos.wire_protocol().participant_id = id;
    bool lost_ports = false;
    {
      const CreatingParticipant creating;
      // Fast DDS ignores a port it could not open (another process took it after the check) and
      // comes up deaf: both ports must be this process's. A participant that lost one is deleted
      // by the thread that made it: deleting may log, and Fast DDS starts its logging thread on
      // first use, at the nice value of the thread that logs.
      // The writer registry listens from the start: it must hear every writer before a reader
      // can match it. Discovery callbacks only (no entity status goes to it).
      const auto create = [&] {
        participant_ = dds::DomainParticipantFactory::get_instance()->create_participant(
            opts.domain_id, pqos, writers_.get(), dds::StatusMask::none());
        if (!participant_) return;
        const auto drop = [&] {
          participant_->set_listener(nullptr);  // it points at writers_, which may be going
          dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
          participant_ = nullptr;
        };
        try {
          if (this_process_holds_udp_port(PortPlan::discovery_port(opts.domain_id, id)) &&
              this_process_holds_udp_port(PortPlan::data_port(opts.domain_id, id)))
            return;
        } catch (...) {
          drop();
          throw;
        }
        drop();
        lost_ports = true;
      };
      if (opts.threads_nice != 0) {
        // Threads inherit their creator's nice value, and an unprivileged process cannot take a
        // raised one back: a helper thread of another nice value creates the participant (and so
        // starts its threads), while this thread keeps its priority.
        std::exception_ptr failed;
        std::thread helper([&] {
          try {
            threads_priority_ = change_thread_nice(opts.threads_nice);
            create();
          } catch (...) {
            failed = std::current_exception();
          }
        });
        helper.join();
        if (failed) std::rethrow_exception(failed);
      } else {
        create();
      }
    }
    if (participant_) break;
    if (!lost_ports)
      throw std::runtime_error("dds: cannot create a participant on domain " +
                               std::to_string(opts.domain_id));
    if (given || attempt >= 16)
      throw std::runtime_error("dds: participant id " + std::to_string(id) + " on domain " +
                               std::to_string(opts.domain_id) +
                               " came up without its unicast ports (taken while it started)");
  }
}

DdsParticipant::~DdsParticipant() {
  if (!participant_) return;
  participant_->set_listener(nullptr);  // waits for a discovery callback in progress
  participant_->delete_contained_entities();
  dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
}

std::string change_thread_nice(int delta) {
  const auto tid = static_cast<id_t>(::gettid());
  errno = 0;
  const int was = ::getpriority(PRIO_PROCESS, tid);
  if (const int error = errno; error != 0)
    return std::string("nice value unknown: ") + std::strerror(error);
  const int want = std::clamp(was + delta, -20, 19);
  if (::setpriority(PRIO_PROCESS, tid, want) != 0) {
    const int error = errno;
    return "nice " + std::to_string(was) + " (cannot change it to " + std::to_string(want) + ": " +
           std::strerror(error) + ")";
  }
  return "nice " + std::to_string(want) + " (was " + std::to_string(was) + ")";
}

std::vector<std::string> ipv4_addresses(const std::string& host, int& error) {
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* res = nullptr;
  error = getaddrinfo(host.c_str(), nullptr, &hints, &res);
  std::vector<std::string> out;
  if (error != 0) return out;
  for (const addrinfo* a = res; a != nullptr; a = a->ai_next) {
    char buf[INET_ADDRSTRLEN] = {};
    inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in*>(a->ai_addr)->sin_addr, buf,
              sizeof buf);
    if (std::find(out.begin(), out.end(), buf) == out.end()) out.emplace_back(buf);
  }
  freeaddrinfo(res);
  if (out.empty()) error = EAI_NODATA;
  return out;
}

std::vector<std::pair<std::string, std::uint16_t>> resolve_discovery_servers(
    const std::string& list) {
  std::vector<std::pair<std::string, std::uint16_t>> out;
  for (const std::string& server : split_names(list))
    out.push_back(resolve_discovery_server(server));
  if (out.empty()) out.push_back(resolve_discovery_server(list));  // "": refused, named
  if (out.size() > kMaxDiscoveryServers)
    throw std::invalid_argument("discovery servers \"" + list + "\": at most " +
                                std::to_string(kMaxDiscoveryServers));
  return out;
}

void add_discovery_servers(const std::vector<std::pair<std::string, std::uint16_t>>& servers,
                           int except, eprosima::fastdds::rtps::RemoteServerList_t& out) {
  for (std::size_t i = 0; i < servers.size(); ++i) {
    if (static_cast<int>(i) == except) continue;
    eprosima::fastdds::rtps::RemoteServerAttributes server;
    eprosima::fastdds::rtps::get_server_client_default_guidPrefix(static_cast<int>(i),
                                                                  server.guidPrefix);
    eprosima::fastrtps::rtps::Locator_t loc;
    eprosima::fastrtps::rtps::IPLocator::setIPv4(loc, servers[i].first);
    loc.port = servers[i].second;
    server.metatrafficUnicastLocatorList.push_back(loc);
    out.push_back(server);
  }
}

std::pair<std::string, std::uint16_t> resolve_discovery_server(const std::string& host_port) {
  const auto colon = host_port.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == host_port.size())
    throw std::invalid_argument("discovery server \"" + host_port + "\": expected HOST:PORT");
  const std::string host = host_port.substr(0, colon);
  const std::string port_text = host_port.substr(colon + 1);
  char* end = nullptr;
  const long port = std::strtol(port_text.c_str(), &end, 10);
  if (*end != '\0' || port < 1 || port > 65535)
    throw std::invalid_argument("discovery server \"" + host_port + "\": port must be 1..65535");
  // A container's name may take a moment to appear in the network's DNS (unknown name, no data,
  // a server failure): retry for ~15 s. A numeric address resolves at once.
  int rc = 0;
  std::vector<std::string> found;
  for (int attempt = 0; attempt < 30; ++attempt) {
    found = ipv4_addresses(host, rc);
    if (rc != EAI_AGAIN && rc != EAI_NONAME && rc != EAI_FAIL && rc != EAI_NODATA) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
  if (found.empty())
    throw std::invalid_argument("discovery server \"" + host_port + "\": cannot resolve " + host +
                                " (" + gai_strerror(rc) + ")");
  return {found.front(), static_cast<std::uint16_t>(port)};
}

}  // namespace qswarm
