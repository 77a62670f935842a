#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "common/core/agent.hpp"

namespace qswarm {

// The DDS names of a run, spelled once: its topics and the partitions that keep one run's samples
// from another's and bind a writer to its agent. The DDS adapter makes its endpoints with them,
// the run plan prints them, and the keystore's permissions grant them (common/app/keystore.hpp).
namespace dds_names {

inline constexpr const char* kStateTopic = "qswarm/agent_state";  // agent to agent
inline constexpr const char* kRecordTopic = "qswarm/record";      // agent to the supervisor
inline constexpr const char* kClaimTopic = "qswarm/id_claim";     // replicas claiming ids

// A topic of the state stream's own for one name of an interest ("a7", a region "rp0.1.0").
std::string state_topic_of(const std::string& name);

// The run's partitions, "qswarm-run-" (state and claims) or "qswarm-record-" (records) and the
// run id's 16 hex digits.
inline constexpr const char* kRunStream = "run";
inline constexpr const char* kRecordStream = "record";
std::string run_partition(std::uint64_t run_id);
std::string record_partition(std::uint64_t run_id);
// Every run's partition of a stream, as a reader's pattern ("qswarm-run-*").
std::string any_run_partition(const char* stream);
// The same as an fnmatch pattern that matches exactly one run's partition name, as DDS-Security's
// permissions name it ("qswarm-run-" and 16 hex digits: "*" would also match "qswarm-run-X/a5").
std::string one_run_pattern(const char* stream);

// Under a run's partition, the one of agent `id` ("qswarm-run-.../a3"): a writer publishing there
// is bound to that agent (the keystore's permissions let agent-ID's certificate publish only
// there among agent partitions). The agent partition itself is interest.hpp's agent_partition.
std::string bound_partition(const std::string& stream_partition, AgentId id);
// The agent a bound partition of the state or record stream names ("qswarm-run-<16 hex>/a3" ->
// 3); nothing for any other name.
std::optional<AgentId> agent_of_bound_partition(const std::string& partition);

}  // namespace dds_names
}  // namespace qswarm
