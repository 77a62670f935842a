#pragma once

#include <optional>
#include <string>
#include <vector>

#include "common/core/agent.hpp"

namespace qswarm {

// Which parts of the run's state stream an endpoint publishes into and listens to: partitions,
// named relative to the run (the transport adds the run's own prefix, so runs stay apart). An
// endpoint hears a sample when the sample's publish set and its subscribe set share a name. The
// empty interest is the whole run: one partition everybody shares.
struct Interest {
  std::vector<std::string> publish;    // sorted, unique
  std::vector<std::string> subscribe;  // sorted, unique
  bool operator==(const Interest&) const = default;
  // Whether a sample published with `from` reaches an endpoint with `to`.
  static bool meets(const Interest& from, const Interest& to);
};

// The partition every agent publishes into, named for its id ("a3"): others listen to it to hear
// that agent by name, and under DDS-Security its certificate's permissions let it publish state
// only there (and in partitions that name no agent), which binds its samples to its id
// (python/qswarm/keys.py writes the permissions; names starting with 'a' are reserved for it).
std::string agent_partition(AgentId id);
// The agent an agent partition names ("a3" -> 3); nothing for any other name ("a03", "a3x").
std::optional<AgentId> agent_of_partition(const std::string& name);

}  // namespace qswarm
