#pragma once

#include <cstdint>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <fastdds/dds/topic/IContentFilterFactory.hpp>

#include "common/core/agent.hpp"

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
// encapsulation header, then the id): checked against a serialized sample by a test.
inline constexpr std::size_t kRosterIdOffset = 4;

// What a reader's roster filter turned away: the first ids, and every sample.
struct StrangerTally {
  static constexpr std::size_t kMaxIds = 64;
  mutable std::mutex mu;
  std::set<AgentId> ids;
  std::uint64_t samples = 0;
};

// The factory of the content filter class kRosterFilterClass, registered on the participant whose
// state reader reads through it: the filter reads the key, the agent id, straight from the
// serialized sample (CDR: a 4-byte encapsulation header, then the id) and admits only the run's
// ids, so a stranger publishing many keys cannot fill the reader's instances. Fast DDS's SQL
// filter was not used: it needs the type's description and decodes every sample in full (a
// 32-agent swarm fell behind real time with it). Counts into its tally.
class RosterFilterFactory final : public eprosima::fastdds::dds::IContentFilterFactory {
 public:
  static constexpr const char* kRosterFilterClass = "QSWARM_ROSTER";
  StrangerTally tally;
  ReturnCode_t create_content_filter(const char* filter_class_name, const char* type_name,
                                     const eprosima::fastdds::dds::TopicDataType* data_type,
                                     const char* expression, const ParameterSeq& params,
                                     eprosima::fastdds::dds::IContentFilter*& filter) override;
  ReturnCode_t delete_content_filter(const char* filter_class_name,
                                     eprosima::fastdds::dds::IContentFilter* filter) override;
};

}  // namespace qswarm
