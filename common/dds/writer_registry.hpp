#pragma once

#include <array>
#include <cstdint>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include <fastdds/dds/domain/DomainParticipantListener.hpp>

#include "common/transport/sample_gate.hpp"

namespace qswarm {

// What discovery says about the other participants' writers of the state and record topics: the
// agent each is bound to, by the agent partition (".../a3") it publishes into. Under DDS-Security
// a writer's partitions are checked against its certificate's permissions when it is discovered,
// and those permissions name one agent (common/app/keystore.hpp), so a writer in ".../a3" holds
// agent 3's certificate: readers then take a sample keyed 3 only from a writer bound to 3.
//
// Fast DDS 2.9.1 checks the partitions again when a writer changes them, but keeps the match it
// already made when the check fails: a writer first bound to 3 that moves to ".../a5" would still
// deliver (docs/fast-dds-workarounds.md, W7). So a writer's binding is the one it was first
// discovered with, and a writer whose partitions ever name another set of agents is bound to
// none, for good.
//
// A writer that publishes into a partition pattern ("qswarm-run-.../*") is bound to none, for
// good. Fast DDS matches partitions with fnmatch both ways, so such a writer reaches every reader
// of the topic, those listening to other agents by name included, and the permissions' rule for
// partitions that name no agent ("[!a]*") admits the pattern itself. The agents' writers publish
// into exact names only (patterns are for readers' cells).
//
// It is the participant's listener from its creation, so that it hears every writer before the
// state reader can match it (discovery calls it before pairing).
class WriterRegistry final : public eprosima::fastdds::dds::DomainParticipantListener {
 public:
  struct Binding {
    bool known = false;            // discovered (and not removed)
    std::optional<AgentId> agent;  // bound to exactly this agent
    std::set<AgentId> named;       // the agents its partitions named when first discovered
    bool changed = false;          // its partitions named other agents since
    bool pattern = false;          // it published into a partition pattern ("*")
  };
  Binding binding(const WriterId& writer) const;
  // Fast DDS's writer GUID as ours (SampleInfo's publication handle holds the same bytes).
  static WriterId id_of(const eprosima::fastrtps::rtps::GUID_t& guid);

  void on_publisher_discovery(eprosima::fastdds::dds::DomainParticipant* participant,
                              eprosima::fastrtps::rtps::WriterDiscoveryInfo&& info) override;

  // The other participants discovery told it of and has not removed: every participant of the run
  // under simple discovery, only those it shares a topic with through a Discovery Server
  // (StateBusOptions::topic_per_name). The agents' stats report it.
  int participants_known() const;
  void on_participant_discovery(eprosima::fastdds::dds::DomainParticipant* participant,
                                eprosima::fastrtps::rtps::ParticipantDiscoveryInfo&& info) override;

 private:
  struct Hash {
    std::size_t operator()(const WriterId& w) const;
  };
  mutable std::mutex mu_;
  std::unordered_map<WriterId, Binding, Hash> writers_;
  std::set<std::array<std::uint8_t, 12>> participants_;  // their GUID prefixes
};

// Whether a partition name may be a pattern to Fast DDS's fnmatch (FNM_NOESCAPE): it holds '*',
// '?' or '[' (a '[' that closes no set is literal, and refused all the same).
bool is_partition_pattern(const std::string& partition);

}  // namespace qswarm
