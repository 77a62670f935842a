#include "common/transport/interest.hpp"

#include <algorithm>

namespace qswarm {

bool Interest::meets(const Interest& from, const Interest& to) {
  if (from.publish.empty() && to.subscribe.empty()) return true;  // both the whole run
  if (from.publish.empty() || to.subscribe.empty()) return false;
  auto a = from.publish.begin(), b = to.subscribe.begin();
  while (a != from.publish.end() && b != to.subscribe.end()) {
    if (*a == *b) return true;
    if (*a < *b) {
      ++a;
    } else {
      ++b;
    }
  }
  return false;
}

std::string agent_partition(AgentId id) { return "a" + std::to_string(id); }

std::optional<AgentId> agent_of_partition(const std::string& name) {
  if (name.size() < 2 || name.size() > 11 || name[0] != 'a' || name[1] == '0') return {};
  std::uint64_t id = 0;
  for (std::size_t i = 1; i < name.size(); ++i) {
    if (name[i] < '0' || name[i] > '9') return {};
    id = id * 10 + static_cast<std::uint64_t>(name[i] - '0');
  }
  if (id > 0xFFFFFFFFULL) return {};
  return static_cast<AgentId>(id);
}

}  // namespace qswarm
