#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "common/clock/clock.hpp"
#include "common/dds/participant.hpp"
#include "common/transport/neighbor_bus.hpp"
#include "common/transport/routing.hpp"
#include "common/transport/sample_gate.hpp"

namespace qswarm {

// The state topic's endpoints on a participant.
struct StateBusOptions {
  int max_agents = 512;  // sizes the keyed reader (Fast DDS defaults cap it at 10 instances)
  bool publish = true;   // false: a reader only (the supervisor publishes nothing)
  // Read the record stream (what agents send the supervisor, topic "qswarm/record") instead of
  // the agents' state stream.
  bool recorder = false;
  // The run: endpoints use the DDS partition qswarm-run-<hex id> and the gate refuses samples of
  // other runs (0: the partition qswarm-run-0, no check).
  std::uint64_t run_id = 0;
  // The run's law: samples of another law, or with a longer payload, are refused.
  ExpectedLaw law;
  // A reader on every run's partition (the supervisor): other runs' samples arrive, are refused
  // as foreign and counted, so that a run can say another one shares its domain.
  bool hear_all_runs = false;
  // The run's agent ids: the reader takes no other key (the roster filter, applied before a
  // sample takes a slot in the reader), so a stranger publishing many keys on the run's partition
  // cannot fill the reader and blind it. Empty: any id.
  std::vector<AgentId> roster;
  // The agent this process flies: its reader does not read its own samples (0: none), and its
  // writers publish into that agent's partition (agent_partition) too, which binds them to it.
  // Under DDS-Security the reader takes a sample keyed K only from a writer bound to K
  // (WriterRegistry): with per-agent permissions a certificate then says which agent it speaks
  // as (a compose keystore's shared member identity may name any: docs/security.md).
  AgentId self = 0;
  // How the state stream reaches those who hear it (transport/routing.hpp, RunPlan::routing):
  // partitions of one topic, or through a Discovery Server, agent names as topics of their own
  // and cells as partitions of the one topic or of region topics. Under the latter two no writer
  // is bound to its agent (Fast DDS 2.9 has no secure Discovery Server), and the gate judges a
  // sample's participant, not its writer, since an agent speaks through several. Their endpoints
  // come with set_interest.
  Routing routing = Routing::kPartitions;
  // The state reader listens on this IPv4 multicast group, at its domain's data multicast port
  // (PortPlan::data_multicast_port), instead of its unicast port: a writer sends each sample
  // once, to the group, instead of once per reader. For a swarm where everyone hears everyone,
  // the only one where that is a saving, since every reader in the group (a run's: see
  // state_multicast_group) receives every datagram sent to it. Needs the participant's interface
  // (one address). Empty: unicast; unicast too, with a warning, where another program holds the
  // group's port alone.
  std::string multicast_group;
};

// The product's NeighborBus: the keyed best-effort topic "qswarm/agent_state" on a participant, a
// keep-last-1 writer and reader. Incoming samples are checked in the listener through the
// SampleGate: bad ones are dropped, counted and logged once per peer; nothing throws out of it.
class DdsStateBus final : public NeighborBus {
 public:
  // `clock`'s wall time judges incarnations from the future (read on DDS threads). The participant
  // must outlive the bus.
  DdsStateBus(DdsParticipant& participant, const StateBusOptions& opts,
              const Clock& clock = system_clock());
  ~DdsStateBus() override;
  DdsStateBus(const DdsStateBus&) = delete;
  DdsStateBus& operator=(const DdsStateBus&) = delete;

  void publish(const StateMessage& msg) override;
  void record(const StateMessage& msg) override;
  // Moves the state writers' and readers' partitions (DDS re-matches them with their peers), and
  // makes and deletes the endpoints of the names that come and go, as its routing says. Where it
  // hears by place stays in this process (its readers' roster filter judges samples on arrival),
  // so that a move updates each reader through discovery once.
  void set_interest(const Interest& interest) override;
  bool recorder_confirmed() const override;
  // Readers matched to our record writer (our side of discovery only: see recorder_confirmed).
  int record_readers_matched() const;
  void for_each_latest(AgentId self,
                       const std::function<void(const StateMessage&)>& visit) override;
  // Called for every accepted sample, on a DDS thread. set_listener(nullptr) waits for a call in
  // progress to finish.
  void set_listener(Listener listener) override;
  BusCounters counters() const override;
  // Readers matched to our writers (DDS discovery; the start barrier waits on it), summed over
  // the writers its routing writes.
  int matched_readers() const override;
  // The readers matched with its writer on a region's topic ("rp1.0.0"), written or idle (0:
  // none). For tests and diagnostics.
  int region_readers_matched(const std::string& region) const;
  // Run ids of other runs heard on this domain (only a hear_all_runs bus hears them).
  std::set<std::uint64_t> foreign_runs() const override;
  // Ids outside the roster whose samples the roster filter dropped (the first 64 of them; their
  // samples are counted in counters().dropped too).
  std::set<AgentId> strangers() const override;
  std::map<AgentId, std::uint8_t> suspects() const override;
  // Samples its place filter judged on arrival.
  std::uint64_t judged_on_arrival() const;
  // The multicast group its state readers listen on: StateBusOptions::multicast_group, or ""
  // where it listens by unicast (none asked for, or the port was held by another program).
  const std::string& multicast_group() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace qswarm
