#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <fastdds/dds/topic/IContentFilterFactory.hpp>

#include "common/core/agent.hpp"
#include "common/transport/interest.hpp"

namespace qswarm {

// What a state reader admits, before a sample is decoded or takes a slot: the run's ids (a
// stranger's samples are counted and dropped), never its own agent's (a process need not read what
// it wrote).
struct RosterExpression {
  std::vector<std::pair<AgentId, AgentId>> ranges;  // inclusive
  AgentId self = 0;                                 // 0: none
  bool operator==(const RosterExpression&) const = default;
};

// The filter's expression: the ids as ranges of consecutive ids ("1-8,10" for 1..8 and 10), then
// ";self=ID" when it is set; and back (nullopt for anything malformed).
std::string roster_filter(std::vector<AgentId> roster, AgentId self = 0);
std::optional<RosterExpression> parse_roster_filter(const std::string& text);

// Where the filter reads the id in a sample (idl/swarm_state.idl, plain CDR: a 4-byte
// encapsulation header, then the id), its consensus state and its physical position (the fixed
// fields before them, each aligned to its size from the end of the header): checked against a
// serialized sample by a test.
inline constexpr std::size_t kRosterIdOffset = 4;
inline constexpr std::size_t kConsensusOffset = 4 + 64;
inline constexpr std::size_t kPositionOffset = 4 + 120;

// Whether a serialized sample names agent `id` among its links, the flows and copies it carries,
// or the peers it asks (mentions() of common/transport/state_message.hpp, read from plain CDR
// without decoding the rest): false for anything that does not parse.
bool serialized_mentions(const unsigned char* data, std::size_t length, AgentId id);

// Where a reader hears by place (Interest::near), and the agents it hears by name wherever they
// are (as ranges of ids). No reach: no place filter.
struct PlaceFilter {
  std::vector<Reach> near;
  std::vector<std::pair<AgentId, AgentId>> names;  // inclusive
  bool operator==(const PlaceFilter&) const = default;
};

// A place filter that DDS threads read while another thread changes it.
struct PlaceSlot {
  mutable std::mutex mu;
  PlaceFilter place;
};

// What a reader's roster filter turned away: the first ids, and every sample.
struct StrangerTally {
  static constexpr std::size_t kMaxIds = 64;
  mutable std::mutex mu;
  std::set<AgentId> ids;
  std::uint64_t samples = 0;
};

// The factory of the content filter class kRosterFilterClass, registered on the participant whose
// state readers read through it: the filter reads the key, the agent id, straight from the
// serialized sample (CDR: a 4-byte encapsulation header, then the id) and admits only the run's
// ids, so a stranger publishing many keys cannot fill the reader's instances; with a place
// (set_local_place), only the senders heard by name or by place, or bound to the reader's agent.
// Fast DDS's SQL filter was not used: it needs the type's description and decodes every sample in
// full (a 32-agent swarm fell behind real time with it). Writers never evaluate it (their
// reader_filters_allocation is 0): Fast DDS 2.9.1 changes a writer's reader filters without its
// lock (docs/fast-dds-workarounds.md, W6), and a writer judging for its readers sends per reader.
class RosterFilterFactory final : public eprosima::fastdds::dds::IContentFilterFactory {
 public:
  static constexpr const char* kRosterFilterClass = "QSWARM_ROSTER";
  StrangerTally tally;
  std::array<std::uint8_t, 12> local{};  // the GUID prefix of the participant it serves
  // Samples the readers' place filters judged on arrival.
  std::atomic<std::uint64_t> judged_on_arrival{0};

  // From now on the readers' filters judge by this place. It stays in this process, not in the
  // filters' parameters, which would travel to every peer through discovery as an update of each
  // reader: a move that also changes the readers' partitions would then update each of them twice
  // at once, which hangs Fast DDS 2.9.1's Discovery Server (docs/fast-dds-workarounds.md, W5).
  void set_local_place(PlaceFilter place);
  const PlaceSlot& local_place() const { return local_place_; }

  ReturnCode_t create_content_filter(const char* filter_class_name, const char* type_name,
                                     const eprosima::fastdds::dds::TopicDataType* data_type,
                                     const char* expression, const ParameterSeq& params,
                                     eprosima::fastdds::dds::IContentFilter*& filter) override;
  ReturnCode_t delete_content_filter(const char* filter_class_name,
                                     eprosima::fastdds::dds::IContentFilter* filter) override;

 private:
  PlaceSlot local_place_;
};

}  // namespace qswarm
