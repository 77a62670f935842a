#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <fastdds/rtps/attributes/ServerAttributes.h>

#include "common/dds/writer_registry.hpp"

namespace eprosima::fastdds::dds {
class DomainParticipant;
class DomainParticipantQos;
}  // namespace eprosima::fastdds::dds

namespace qswarm {

class TickReceive;

// How a process's one DDS participant is made: where its traffic may go, how it discovers.
struct ParticipantOptions {
  std::uint32_t domain_id = 0;
  std::string name = "qswarm";
  // DDS traffic stays on this interface (loopback by default: nothing leaves the host). Empty:
  // every interface (inside a container).
  std::string interface = "127.0.0.1";
  bool shared_memory = false;  // off by default: faults below the application must bite
  // Fast DDS's test transport instead of plain UDPv4: drop this percentage of data messages on
  // the sending side (0 = plain UDPv4).
  std::uint8_t test_drop_data_percent = 0;
  // The test transport too, dropping every writer announcement this participant sends (DATA(w)):
  // its peers never learn its writers while it learns their readers, a lost discovery message
  // made permanent (tests of a one-sided match).
  bool test_drop_writer_announcements = false;
  // Fast DDS Discovery Servers "HOST:PORT[,HOST:PORT...]" (HOST a name or an IPv4 address):
  // discover through them as a client instead of by multicast (container networks, hosts without
  // multicast); with two, either one alone keeps discovery going. Empty: simple discovery.
  std::string discovery_server;
  // Its participant id in the port plan (PortPlan): a given id whose ports are taken is an error;
  // -1 takes the highest id whose ports are free (runs reserve their blocks from 0 up).
  int participant_id = -1;
  // Discovery by unicast alone, to the participant ids [first, first + count) of the port plan
  // on `interface` (a run's block, which the launcher reserves): no multicast is sent or heard.
  // Secure runs need it: Fast DDS 2.9.1 matches a newly authenticated peer's built-in secure
  // endpoints through shared temporary records (SecurityManager's temp_*_proxy_data_, fixed in
  // 2.9.2), and with multicast beside unicast two receive threads can fill them for two peers at
  // once; the pair whose records got mixed never exchanges keys (docs/fast-dds-workarounds.md, W2).
  // With one metatraffic socket they are filled one at a time.
  // count 0: multicast discovery (simple), as Fast DDS does by default.
  int unicast_peers_first = 0;
  int unicast_peers_count = 0;
  // Where those ids are: these IPv4 addresses, each with the ids' ports (compose replicas, one
  // participant per container, found by name: find_peer_hosts). Empty: `interface`, which may
  // then be empty (every interface) here.
  std::vector<std::string> unicast_peer_hosts;
  // How often it announces itself after its first quick announcements (seconds): everyone hears
  // every announcement, so a large swarm announces less often.
  double announce_period_s = 1.0;
  // Fast DDS's threads (receive, events, discovery) run this much nicer than the thread that
  // creates the participant: when the CPU is short, that thread (an agent's tick) goes first and
  // samples wait in their sockets, where the newest one wins anyway. 0: the same priority.
  // Negative: ahead of it, where the host allows it (root, or RLIMIT_NICE); elsewhere they keep
  // its priority. threads_priority() says which. Only the threads the participant starts as it is
  // made: a thread Fast DDS starts later (a reader's own multicast receive thread, started by the
  // thread that makes the reader) runs at its maker's priority.
  int threads_nice = 0;
  // DDS-Security: a keystore written by `swarm keys` and the identity in it this participant
  // speaks as ("agent-3", "supervisor"). Empty keystore: a plain participant. Fast DDS 2.9 has no
  // secure Discovery Server: the two together are refused.
  std::string keystore;
  std::string identity;
  // Receive without Fast DDS's receive threads (TickReceive): the thread that owns the loop reads
  // the sockets (drain_receive()) once a tick. false: Fast DDS's UDPv4, a thread per locator.
  bool tick_receive = false;
};

// One DomainParticipant with the project's settings: transports (one UDPv4 on the allowed
// interface, or the test transport; shared memory on request), discovery (simple, or a Discovery
// Server's client), an infinite lease announced every second, and room for many participants on
// one host. The endpoints (the state bus, the claim bus) are made on it and must be deleted before
// it. This is where participant-wide settings (a port plan, security) belong.
class DdsParticipant {
 public:
  explicit DdsParticipant(const ParticipantOptions& opts);
  ~DdsParticipant();
  DdsParticipant(const DdsParticipant&) = delete;
  DdsParticipant& operator=(const DdsParticipant&) = delete;

  eprosima::fastdds::dds::DomainParticipant* get() const { return participant_; }
  const ParticipantOptions& options() const { return opts_; }
  bool secure() const { return !opts_.keystore.empty(); }
  // The other participants' state and record writers, and the agent each is bound to.
  const WriterRegistry& writers() const { return *writers_; }
  // What Fast DDS's threads run at, for the log ("" with threads_nice 0).
  const std::string& threads_priority() const { return threads_priority_; }
  // With tick_receive: what reads its sockets (drain() each tick); null otherwise.
  TickReceive* tick_receive() const { return tick_rx_.get(); }

 private:
  std::shared_ptr<TickReceive> tick_rx_;
  ParticipantOptions opts_;
  std::unique_ptr<WriterRegistry> writers_ = std::make_unique<WriterRegistry>();
  eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
  std::string threads_priority_;
};

// Changes the calling thread's nice value by `delta` (negative: a higher priority), before it
// starts threads, which inherit it; says what it runs at, or why it kept its priority (an
// unprivileged process may not raise it).
std::string change_thread_nice(int delta);

// Turns off the writer liveliness protocol (two reliable endpoints matched with every discovered
// participant): no writer of the project asserts liveliness (every one keeps the default infinite
// lease), and agents judge a silent neighbour by their own timeout.
void disable_writer_liveliness(eprosima::fastdds::dds::DomainParticipantQos& qos);

// The Discovery Server's address as Fast DDS wants it: "HOST:PORT" with HOST resolved to IPv4
// (with retries for ~15 s while a container network's DNS catches up). Throws
// std::invalid_argument naming what is wrong.
std::pair<std::string, std::uint16_t> resolve_discovery_server(const std::string& host_port);
// A list of servers, "HOST:PORT[,HOST:PORT...]" (at most kMaxDiscoveryServers), each resolved as
// above. A server's place in the list is its index: the GUID prefix a client expects of it
// (Fast DDS's default prefix for server i), so every process must list the servers in one order.
inline constexpr std::size_t kMaxDiscoveryServers = 4;
std::vector<std::pair<std::string, std::uint16_t>> resolve_discovery_servers(
    const std::string& list);

// The servers of that list as Fast DDS's remote servers, each with its index's prefix, but the one
// at `except` (a server itself: -1 for none).
void add_discovery_servers(const std::vector<std::pair<std::string, std::uint16_t>>& servers,
                           int except, eprosima::fastdds::rtps::RemoteServerList_t& out);

// Every IPv4 address `host` resolves to now (a numeric address: itself), in the resolver's order
// without repeats; empty, with `error` set to getaddrinfo's code, when it does not resolve.
std::vector<std::string> ipv4_addresses(const std::string& host, int& error);

// Whether a thread of this process is inside Fast DDS's participant creation. When a thread of
// the participant cannot start (a task limit), Fast DDS 2.9 throws, and a destructor on the way
// out throws again (std::thread::join on the thread that never started: "Invalid argument"), which
// ends in std::terminate: the terminate handler says what it was from this.
bool creating_participant();

}  // namespace qswarm
