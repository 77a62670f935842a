#pragma once

#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <utility>

namespace qswarm {

// Where DDS participants listen on one host: the project's port plan. Fast DDS numbers a
// participant's unicast ports from its domain and participant id (7410 + domain gain x domain +
// 2 x id for discovery, one more for data); with its default domain gain of 250, ids of 120 and up
// spill into the next domain's ports. The plan gives each domain a block of 1100 ports, room for
// participant ids 0 to 544 (the largest swarm, 512 agents, and its supervisor; or two runs of
// 256), and multicast discovery at the block's start (domain 0: Fast DDS's default 7400). Ports
// stay below 32768, where Linux hands out ephemeral ports (ip_local_port_range 32768-60999): a
// planned port inside that range is taken at random by any socket bound to port 0 on the host (the
// 64-agent test lost an agent so on domain 41), so domains 0 to 22.
struct PortPlan {
  static constexpr std::uint32_t kBase = 7400;
  static constexpr std::uint32_t kDomainGain = 1100;
  static constexpr std::uint32_t kParticipantGain = 2;
  static constexpr std::uint32_t kMaxDomain = 22;
  static constexpr int kMaxParticipantId = 544;

  // The discovery (metatraffic) and data unicast ports of participant `id` on `domain`.
  static constexpr std::uint32_t discovery_port(std::uint32_t domain, int id) {
    return kBase + kDomainGain * domain + 10 + kParticipantGain * static_cast<std::uint32_t>(id);
  }
  static constexpr std::uint32_t data_port(std::uint32_t domain, int id) {
    return discovery_port(domain, id) + 1;
  }
  // The domain's multicast ports: discovery (Fast DDS's own), and the state readers' group
  // (StateBusOptions::multicast_group), the port Fast DDS gives user data multicast.
  static constexpr std::uint32_t discovery_multicast_port(std::uint32_t domain) {
    return kBase + kDomainGain * domain;
  }
  static constexpr std::uint32_t data_multicast_port(std::uint32_t domain) {
    return discovery_multicast_port(domain) + 1;
  }
};
static_assert(PortPlan::data_port(PortPlan::kMaxDomain, PortPlan::kMaxParticipantId) < 32768,
              "the port plan must stay below Linux's ephemeral ports");

// The multicast group of a run's state readers where everyone hears everyone
// (StateBusOptions::multicast_group): 239.255.A.B from the run id, never 239.255.0.x (Fast DDS's
// discovery group). Fast DDS binds a group's socket to the group's address, so the kernel hands
// a run's agents only their own run's datagrams, though runs share the domain's port.
std::string state_multicast_group(std::uint64_t run_id);

// Whether sockets may share `port` at the multicast `group` and at `address` (SO_REUSEADDR, as
// Fast DDS binds multicast sockets): "" if so, else why not (a program holds the port alone).
std::string multicast_port_problem(const std::string& group, std::uint32_t port,
                                   const std::string& address);

// Parses a block of participant ids "FIRST:COUNT" (all within 0..kMaxParticipantId): what
// --unicast-peers takes. Nothing, with `why`, if it is not one.
std::optional<std::pair<int, int>> parse_unicast_peers(const std::string& text, std::string& why);

// Why participant `id` cannot listen on `domain` at `address` now ("" if it can): one of its two
// unicast ports is taken (another run on this domain, or another program).
std::string participant_ports_problem(std::uint32_t domain, int id, const std::string& address);

// Whether a UDP socket of this process is bound to `port` (read from /proc: a port that merely
// cannot be bound may be another process's).
bool this_process_holds_udp_port(std::uint32_t port);

// The first participant id of a block of `count` consecutive ids whose ports are all free on
// `domain` at `address`, trying blocks from `first`; nothing if the domain has no such room.
std::optional<int> free_participant_block(std::uint32_t domain, int count,
                                          const std::string& address, int first = 0);

// A run's block of participant ids, held for the life of this object (the launcher's): a file per
// block under `registry` (default /tmp/qswarm-ports) names the domain, the ids and the holder's
// pid, and blocks are chosen under a lock on that folder, so that two launchers started at once
// never choose the same ids, and a killed agent's ids stay the run's until it restarts. A
// holder that died leaves a stale file, which the next choice ignores and removes.
class PortReservation {
 public:
  // Chooses and holds the first block of `count` ids on `domain` that no live holder reserved
  // and whose ports are free at `address`; nothing if the domain has no such room. Throws
  // std::runtime_error if the registry cannot be used (naming it).
  static std::optional<PortReservation> reserve(std::uint32_t domain, int count,
                                                const std::string& address,
                                                const std::string& registry = kRegistry);
  PortReservation(PortReservation&& o) noexcept : base_(o.base_), file_(std::move(o.file_)) {
    o.file_.clear();
  }
  PortReservation& operator=(PortReservation&&) = delete;
  PortReservation(const PortReservation&) = delete;
  PortReservation& operator=(const PortReservation&) = delete;
  ~PortReservation();
  int base() const { return base_; }

  static constexpr const char* kRegistry = "/tmp/qswarm-ports";

 private:
  PortReservation(int base, std::string file) : base_(base), file_(std::move(file)) {}
  int base_;
  std::string file_;
};

// The IPv4 addresses this machine's interfaces hold ("127.0.0.1", ...); none when it cannot tell.
std::set<std::string> local_ipv4_addresses();

}  // namespace qswarm
