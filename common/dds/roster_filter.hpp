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

// Where a reader hears by place (Interest::near), in the filter's parameters, which the reader
// may change while it runs (its peers' writers learn them through discovery and filter with
// them; kept in the process instead where they do not, RosterFilterFactory::set_local_place):
// one parameter per Reach ("p LO.x LO.y LO.z HI.x HI.y HI.z RADIUS", 'q' for consensus
// states) and the agents it hears by name as ranges ("n 1-3,9"; several parameters when that is
// longer than Fast DDS's 255 characters a parameter). No parameter: no place filter.
struct PlaceFilter {
  std::vector<Reach> near;
  std::vector<std::pair<AgentId, AgentId>> names;  // inclusive
  bool operator==(const PlaceFilter&) const = default;
};
std::vector<std::string> place_filter(const std::vector<Reach>& near,
                                      const std::vector<AgentId>& names);
// Nothing for anything malformed: an unknown kind, a number that is not finite, a negative radius,
// a box upside down, more than 64 parameters, names with no place.
std::optional<PlaceFilter> parse_place_filter(const std::vector<std::string>& params);

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
// state reader reads through it, and on every agent's, whose state writer evaluates its peers'
// readers' filters: the filter reads the key, the agent id, straight from the serialized sample
// (CDR: a 4-byte encapsulation header, then the id) and admits only the run's ids, so a stranger
// publishing many keys cannot fill the reader's instances; with a place filter (in its
// parameters, or the factory's local place), only the senders heard by name or by place, or bound
// to it. Fast DDS's SQL filter was not used: it needs the type's description and decodes every
// sample in full (a 32-agent swarm fell behind real time with it). The parameters change in place
// (receive threads and writers evaluate the filter meanwhile); the expression never does. Counts
// strangers into its tally for the readers of the participant `local` names (a writer evaluating a
// peer's filter counts nothing).
class RosterFilterFactory final : public eprosima::fastdds::dds::IContentFilterFactory {
 public:
  static constexpr const char* kRosterFilterClass = "QSWARM_ROSTER";
  StrangerTally tally;
  std::array<std::uint8_t, 12> local{};  // the GUID prefix of the participant it serves
  // Samples the local readers' place filters judged on arrival: none once the writers filter for
  // them (a sample a writer judged carries its verdict), only those of writers that do not.
  std::atomic<std::uint64_t> judged_on_arrival{0};

  // From now on the local readers' filters judge by this place, not by their parameters, and
  // set_local_place changes it without discovery. For readers no writer filters for
  // (StateBusOptions::filter_at_writer false), which need not tell anyone where they listen: new
  // parameters travel to every peer as an update of each reader, and a move that also changes
  // the readers' partitions would then update each of them twice at once. Fast DDS 2.9.1's
  // Discovery Server releases the first of two updates of one endpoint that reach it together
  // while it still means to relay it, and corrupts its history (docs/architecture.md, "A hung
  // Discovery Server").
  void set_local_place(PlaceFilter place);
  // Whether set_local_place was called.
  bool place_is_local() const { return place_is_local_.load(std::memory_order_acquire); }
  const PlaceSlot& local_place() const { return local_place_; }

  ReturnCode_t create_content_filter(const char* filter_class_name, const char* type_name,
                                     const eprosima::fastdds::dds::TopicDataType* data_type,
                                     const char* expression, const ParameterSeq& params,
                                     eprosima::fastdds::dds::IContentFilter*& filter) override;
  ReturnCode_t delete_content_filter(const char* filter_class_name,
                                     eprosima::fastdds::dds::IContentFilter* filter) override;

 private:
  PlaceSlot local_place_;
  std::atomic<bool> place_is_local_{false};
};

}  // namespace qswarm
