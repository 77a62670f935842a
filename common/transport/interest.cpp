#include "common/transport/interest.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <set>
#include <utility>

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

namespace {

// A cell's name ("p-1.0.2") taken apart: its tag and indices; nothing for any other name.
std::optional<std::pair<char, std::array<std::int64_t, 3>>> parse_cell(const std::string& name) {
  if (name.size() < 6 || (name[0] != 'p' && name[0] != 'q')) return std::nullopt;
  long long x = 0, y = 0, z = 0;
  int used = 0;
  if (std::sscanf(name.c_str() + 1, "%lld.%lld.%lld%n", &x, &y, &z, &used) != 3 ||
      static_cast<std::size_t>(used) + 1 != name.size())
    return std::nullopt;
  const std::array<std::int64_t, 3> c{x, y, z};
  for (const std::int64_t v : c)
    if (v < -(std::int64_t{1} << 31) || v >= (std::int64_t{1} << 31)) return std::nullopt;
  return std::make_pair(name[0], c);
}

std::string hex8(std::int64_t index) {
  char buf[12];
  std::snprintf(buf, sizeof buf, "%08llx", static_cast<unsigned long long>(index) + (1ULL << 31));
  return buf;
}

// A cell's name on the wire, or a pattern of them: the tag and the three axes' parts.
std::string wire_name(char tag, const std::string& x, const std::string& y, const std::string& z) {
  std::string out(1, tag);
  out.append(x).append(1, '.').append(y).append(1, '.').append(z);
  return out;
}

// fnmatch patterns that match exactly the indices lo..hi in hex8 form: one per run of indices
// that share all but the last digit, the last digits listed ("8000000[0123]").
std::vector<std::string> range_patterns(std::int64_t lo, std::int64_t hi) {
  std::vector<std::string> out;
  for (std::int64_t v = lo; v <= hi;) {
    const std::string h = hex8(v);
    std::string last;
    do {
      last += hex8(v).back();
      ++v;
    } while (v <= hi && hex8(v).compare(0, 7, h, 0, 7) == 0);
    std::string p = h.substr(0, 7);
    if (last.size() == 1) {
      p += last;
    } else {
      p.append(1, '[').append(last).append(1, ']');
    }
    out.push_back(std::move(p));
  }
  return out;
}

}  // namespace

namespace {
std::int64_t floor_div(std::int64_t a, std::int64_t b) { return a / b - ((a % b != 0) && (a < 0)); }

std::string cell_text(char tag, std::int64_t x, std::int64_t y, std::int64_t z) {
  char buf[80];
  std::snprintf(buf, sizeof buf, "%c%lld.%lld.%lld", tag, static_cast<long long>(x),
                static_cast<long long>(y), static_cast<long long>(z));
  return buf;
}
}  // namespace

std::optional<std::string> region_of_cell(const std::string& name) {
  const auto cell = parse_cell(name);
  if (!cell) return std::nullopt;
  const auto& c = cell->second;
  return "r" + cell_text(cell->first, floor_div(c[0], kRegionCells), floor_div(c[1], kRegionCells),
                         floor_div(c[2], kRegionCells));
}

std::vector<std::string> cells_about(const std::string& cell, int span) {
  std::vector<std::string> out;
  const auto parsed = parse_cell(cell);
  if (!parsed) return out;
  const auto& c = parsed->second;
  for (int dx = -span; dx <= span; ++dx)
    for (int dy = -span; dy <= span; ++dy)
      for (int dz = -span; dz <= span; ++dz)
        out.push_back(cell_text(parsed->first, c[0] + dx, c[1] + dy, c[2] + dz));
  return out;
}

std::vector<std::string> dds_partition_names(const std::vector<std::string>& names, bool patterns) {
  std::vector<std::string> out;
  std::map<char, std::set<std::array<std::int64_t, 3>>> cells;
  for (const std::string& n : names) {
    const auto cell = parse_cell(n);
    if (!cell) {
      out.push_back(n);
    } else if (!patterns) {
      const auto& c = cell->second;
      out.push_back(wire_name(cell->first, hex8(c[0]), hex8(c[1]), hex8(c[2])));
    } else {
      cells[cell->first].insert(cell->second);
    }
  }
  for (const auto& [tag, set] : cells) {
    std::array<std::int64_t, 3> lo = *set.begin(), hi = lo;
    for (const auto& c : set)
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], c[k]);
        hi[k] = std::max(hi[k], c[k]);
      }
    const auto side = [&](int k) { return static_cast<std::uint64_t>(hi[k] - lo[k] + 1); };
    const bool fills = side(0) <= set.size() && side(1) <= set.size() && side(2) <= set.size() &&
                       side(0) * side(1) * side(2) == set.size();
    if (fills) {
      for (const std::string& x : range_patterns(lo[0], hi[0]))
        for (const std::string& y : range_patterns(lo[1], hi[1]))
          for (const std::string& z : range_patterns(lo[2], hi[2]))
            out.push_back(wire_name(tag, x, y, z));
    } else {
      for (const auto& c : set) out.push_back(wire_name(tag, hex8(c[0]), hex8(c[1]), hex8(c[2])));
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace qswarm
