#pragma once

#include <string>
#include <vector>

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

}  // namespace qswarm
