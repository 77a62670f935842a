#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "common/claim/claim_bus.hpp"
#include "common/clock/clock.hpp"
#include "common/transport/neighbor_bus.hpp"

namespace qswarm {

struct DdsOptions {
  std::uint32_t domain_id = 0;
  std::string participant_name = "qswarm";
  // DDS traffic stays on this interface (loopback by default: nothing leaves the host).
  std::string interface = "127.0.0.1";
  bool shared_memory = false;  // off by default: faults below the application must bite
  int max_agents = 512;        // sizes the keyed reader (Fast DDS defaults cap it at 10 instances)
  bool publish = true;         // false: a read-only participant (the supervisor)
  // Fast DDS's test transport instead of plain UDPv4: drop this percentage of data messages on
  // the sending side (0 = plain UDPv4).
  std::uint8_t test_drop_data_percent = 0;
  // The run: endpoints use the DDS partition qswarm-run-<hex id> and the gate refuses samples of
  // other runs (0: the partition qswarm-run-0, no check).
  std::uint64_t run_id = 0;
  // A reader on every run's partition (the supervisor): other runs' samples arrive, are refused
  // as foreign and counted, so that a run can say another one shares its domain.
  bool hear_all_runs = false;
  // Also join the id-claim topic "qswarm/id_claim" (swarm-agent --id auto, the compose swarm).
  bool id_claims = false;
  // The run's agent ids: the state reader takes no other key (a DDS content filter, applied before
  // a sample takes a slot in the reader), so a stranger publishing many keys on the run's partition
  // cannot fill the reader and blind it. Empty: any id.
  std::vector<AgentId> roster;
  // Fast DDS Discovery Server "HOST:PORT" (HOST a name or an IPv4 address): discover through it as
  // a client instead of by multicast (container networks). Empty: the standard simple discovery.
  std::string discovery_server;
};

// The Discovery Server's address as Fast DDS wants it: "HOST:PORT" with HOST resolved to IPv4.
// Throws std::invalid_argument naming what is wrong.
std::pair<std::string, std::uint16_t> resolve_discovery_server(const std::string& host_port);

std::string run_partition(std::uint64_t run_id);

// The roster filter's expression: the ids as ranges of consecutive ids ("1-8,10" for 1..8 and 10;
// empty for an empty roster), and back (nullopt for anything else).
std::string roster_filter(std::vector<AgentId> roster);
std::optional<std::vector<std::pair<AgentId, AgentId>>> parse_roster_filter(
    const std::string& expr);

// The product's NeighborBus: one DomainParticipant, the keyed best-effort state topic
// "qswarm/agent_state", a keep-last-1 writer and reader. Incoming samples are checked in the
// listener through the SampleGate: bad ones are dropped, counted and logged once per peer;
// nothing throws out of it.
class DdsBus final : public NeighborBus, public ClaimBus {
 public:
  // `clock`'s wall time judges incarnations from the future (read on DDS threads).
  explicit DdsBus(const DdsOptions& opts, const Clock& clock = system_clock());
  ~DdsBus() override;
  DdsBus(const DdsBus&) = delete;
  DdsBus& operator=(const DdsBus&) = delete;

  void publish(const StateMessage& msg) override;
  std::vector<StateMessage> latest(AgentId self) override;
  // Called for every accepted sample, on a DDS thread. set_listener(nullptr) waits for a call in
  // progress to finish.
  void set_listener(Listener listener) override;
  BusCounters counters() const override;
  // Number of readers matched to our writer (DDS discovery; the start barrier waits on it).
  int matched_readers() const override;
  // Run ids of other runs heard on this domain (only a hear_all_runs bus hears them).
  std::set<std::uint64_t> foreign_runs() const override;
  // Ids outside the roster whose samples the roster filter dropped (the first 64 of them; their
  // samples are counted in counters().dropped too).
  std::set<AgentId> strangers() const override;
  // The id-claim topic (DdsOptions::id_claims): announce this replica's claim, and the latest
  // claim of every replica heard (a bounded number of them: strangers cannot grow it).
  void publish_claim(const IdClaim& claim) override;
  std::vector<IdClaim> claims() const override;
  // Claim writers matched to this participant's claim reader (its own included).
  int claim_writers_matched() const override;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace qswarm
