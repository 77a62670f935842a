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
  // The agent names of an interest (set_interest: "a7") become topics of their own
  // ("qswarm/agent_state/a7"), not partitions of the shared topic, and cells partitions of their
  // region's topic ("qswarm/agent_state/rp0.1.0": region_of_cell). For a Discovery Server client:
  // the server relays a participant's announcement only to participants with an endpoint on a
  // topic it uses (partitions are matched by the clients, after discovery), so an agent that
  // hears its neighbours by name (a FIXED graph) discovers only them, and one that hears by place
  // the agents of the regions about it, not the swarm. Cells are not topics of their own because
  // a move between topics would replace the writer, and its readers would hear it only once the
  // server has relayed the new one (a 64-agent formation lost neighbours and, once in five runs,
  // edge-flow's exact average that way): an agent keeps idle writers, already matched, on the
  // regions within a cell of its own. Cells are region topics only with `region_topics`, else
  // partitions of the shared topic. No binding of writers
  // to agents (the agent partitions DDS-Security's permissions name; Fast DDS 2.9 has no secure
  // Discovery Server); the gate judges a sample's participant, not its writer, since an agent
  // speaks through two. Until set_interest the state stream has no endpoints.
  bool topic_per_name = false;
  // With topic_per_name, cells are partitions of their region's topic rather than of the shared
  // one (where the interest's cells are of one space). Each move then updates up to 8 readers and
  // several writers through the server instead of one of each. Fast DDS 2.9.1's server corrupts
  // its history, hangs and relays nothing more when two changes of one endpoint reach it in one
  // batch (docs/architecture.md, "A hung Discovery Server"): a move changes each endpoint once
  // (twice with filter_at_writer: partitions, then the place in the filter's parameters), but two
  // moves a few ticks apart still can, the more often the less CPU the server gets.
  // Worth it only where the shared topic cannot discover at all (256 agents: 159 s).
  bool region_topics = false;
  // The state writer evaluates its readers' place filters (Interest::near) and sends a sample only
  // to the readers it passes (Fast DDS's writer-side content filtering, for up to max_agents + 16
  // readers), so an agent is sent only what it hears. Each sample then carries 16 bytes per
  // filtering reader its writer is matched with, and is judged once per reader: worth it where
  // agents hear by place (a proximity or radio-range graph), not on a fixed graph. False: readers
  // filter what they are sent.
  // The product leaves it false: Fast DDS 2.9.1 adds and removes a writer's reader filters from
  // its discovery thread without the writer's lock (the RTPS writer calls its listener unlocked)
  // while write() walks the same map, so a reader matched or unmatched during a write (an agent
  // changing cells, joining, leaving) can corrupt it. Fast DDS 3.0.0 locks there (#21188).
  bool filter_at_writer = false;
  // The state reader listens on this IPv4 multicast group, at its domain's data multicast port
  // (PortPlan::data_multicast_port), instead of its unicast port: a writer sends each sample
  // once, to the group, instead of once per reader. For a swarm where everyone hears everyone,
  // the only one where that is a saving, since every reader in the group (a run's: see
  // state_multicast_group) receives every datagram sent to it. Needs the participant's interface
  // (one address). Empty: unicast; unicast too, with a warning, where another program holds the
  // group's port alone.
  std::string multicast_group;
};

// The DDS partitions of a run: the agents' state stream, and the record stream to the supervisor.
std::string run_partition(std::uint64_t run_id);
std::string record_partition(std::uint64_t run_id);

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
  // Moves the state writer's and reader's partitions (DDS re-matches them with their peers); with
  // topic_per_name, creates and deletes the writers and readers of the names that come and go.
  // Where it hears by place goes into its readers' filter: into the filter's parameters, which its
  // peers' writers learn through discovery, only where they judge it (filter_at_writer); else it
  // stays in this process, and a move updates each reader through discovery once.
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
  // Readers matched to our writer (DDS discovery; the start barrier waits on it); with
  // topic_per_name, summed over the writers of its names.
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
  // Samples its place filter judged on arrival (StateBusOptions::filter_at_writer: none, since
  // each writer judges before it sends).
  std::uint64_t judged_on_arrival() const;
  // The multicast group its state readers listen on: StateBusOptions::multicast_group, or ""
  // where it listens by unicast (none asked for, or the port was held by another program).
  const std::string& multicast_group() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace qswarm
