#include "common/transport/interest.hpp"

#include <algorithm>
#include <cmath>

namespace qswarm {
namespace {

// Calls f(name) for every name both sorted lists hold, until f returns true; returns whether one
// did.
template <typename F>
bool any_shared(const std::vector<std::string>& a, const std::vector<std::string>& b, F f) {
  auto i = a.begin(), j = b.begin();
  while (i != a.end() && j != b.end()) {
    if (*i == *j) {
      if (f(*i)) return true;
      ++i;
      ++j;
    } else if (*i < *j) {
      ++i;
    } else {
      ++j;
    }
  }
  return false;
}

}  // namespace

bool Reach::contains(const Vec3& x) const {
  if (!x.allFinite()) return false;
  double d2 = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double out = std::max({lo[k] - x[k], 0.0, x[k] - hi[k]});
    d2 += out * out;
  }
  return d2 <= radius_m * radius_m;
}

bool Interest::meets(const Interest& from, const Interest& to) {
  if (from.publish.empty() && to.subscribe.empty()) return true;  // both the whole run
  if (from.publish.empty() || to.subscribe.empty()) return false;
  return any_shared(from.publish, to.subscribe, [](const std::string&) { return true; });
}

std::optional<AgentId> Interest::agent() const {
  for (const std::string& n : publish)
    if (const auto id = agent_of_partition(n)) return id;
  return std::nullopt;
}

bool Interest::hears(const Interest& to, const Interest& from, const Vec3& q, const Vec3& p_W,
                     bool bonded) {
  if (from.publish.empty() && to.subscribe.empty()) return true;
  if (from.publish.empty() || to.subscribe.empty()) return false;
  bool by_cell = false;
  const bool by_name = any_shared(from.publish, to.subscribe, [&](const std::string& n) {
    if (agent_of_partition(n)) return true;
    by_cell = true;
    return false;
  });
  if (by_name) return true;
  if (!by_cell) return false;
  return to.near.empty() || bonded ||
         std::any_of(to.near.begin(), to.near.end(),
                     [&](const Reach& r) { return r.contains(r.space == 'q' ? q : p_W); });
}

namespace {
// The id after `prefix` ("a3" -> 3 for "a"): digits, no leading zero, within 32 bits.
std::optional<AgentId> id_after(const std::string& name, const std::string& prefix) {
  const std::size_t n = prefix.size();
  if (name.size() < n + 1 || name.size() > n + 10 || name.compare(0, n, prefix) != 0 ||
      name[n] == '0')
    return {};
  std::uint64_t id = 0;
  for (std::size_t i = n; i < name.size(); ++i) {
    if (name[i] < '0' || name[i] > '9') return {};
    id = id * 10 + static_cast<std::uint64_t>(name[i] - '0');
  }
  if (id > 0xFFFFFFFFULL) return {};
  return static_cast<AgentId>(id);
}
}  // namespace

std::string agent_partition(AgentId id) { return "a" + std::to_string(id); }

std::optional<AgentId> agent_of_partition(const std::string& name) { return id_after(name, "a"); }

std::string inbox_partition(AgentId id) { return "in" + std::to_string(id); }

std::optional<AgentId> inbox_of_partition(const std::string& name) { return id_after(name, "in"); }

}  // namespace qswarm
