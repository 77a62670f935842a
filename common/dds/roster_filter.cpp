#include "common/dds/roster_filter.hpp"

#include <fastdds/dds/topic/IContentFilter.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <sstream>

namespace qswarm {

namespace dds = eprosima::fastdds::dds;

namespace {

std::uint64_t read_uint(const unsigned char* d, std::size_t at, std::size_t bytes, bool little) {
  std::uint64_t v = 0;
  for (std::size_t k = 0; k < bytes; ++k) {
    const std::size_t i = little ? at + bytes - 1 - k : at + k;
    v = v << 8 | d[i];
  }
  return v;
}

Vec3 read_vec3(const unsigned char* d, std::size_t at, bool little) {
  Vec3 v;
  for (int k = 0; k < 3; ++k) {
    const std::uint64_t bits = read_uint(d, at + 8 * static_cast<std::size_t>(k), 8, little);
    double x = 0.0;
    std::memcpy(&x, &bits, sizeof x);
    v[k] = x;
  }
  return v;
}

bool in_ranges(const std::vector<std::pair<AgentId, AgentId>>& ranges, AgentId id) {
  return std::any_of(ranges.begin(), ranges.end(),
                     [id](const auto& r) { return id >= r.first && id <= r.second; });
}

// A read position in a plain CDR sample: alignment counts from the end of the 4-byte
// encapsulation header.
struct Cdr {
  const unsigned char* d;
  std::size_t length;
  bool little;
  std::size_t at = 4;
  bool ok = true;
  void align(std::size_t n) { at = 4 + (at - 4 + n - 1) / n * n; }
  void skip(std::size_t n) {
    if (at + n > length) ok = false;
    at = ok ? at + n : length;
  }
  std::uint32_t u32() {
    align(4);
    if (at + 4 > length) ok = false;
    if (!ok) return 0;
    const auto v = static_cast<std::uint32_t>(read_uint(d, at, 4, little));
    at += 4;
    return v;
  }
  // A sequence's length, no more than the IDL's bound.
  std::uint32_t count(std::uint32_t bound) {
    const std::uint32_t n = u32();
    if (n > bound) ok = false;
    return ok ? n : 0;
  }
};

constexpr std::size_t kStrangersOffset = 4 + 304;  // after the fixed fields (idl/swarm_state.idl)
constexpr std::uint32_t kMaxEntries = 511;

// The ids a serialized sample mentions (its links, flows, copies and asking), in order; nothing
// if it does not parse.
std::vector<AgentId> mentioned_ids(const unsigned char* d, std::size_t length) {
  std::vector<AgentId> out;
  if (d == nullptr || length < kStrangersOffset) return out;
  Cdr c{d, length, (d[1] & 1) != 0};
  c.at = kStrangersOffset;
  c.skip(4 * std::size_t{c.count(16)});                      // strangers
  for (std::uint32_t n = c.count(16); c.ok && n > 0; --n) {  // suspects: {id, kinds}
    c.u32();
    c.skip(1);
  }
  const auto links = [&](bool keep) {
    for (std::uint32_t n = c.count(kMaxEntries); c.ok && n > 0; --n) {
      const AgentId peer = c.u32();
      c.align(8);
      c.skip(8);  // weight
      if (keep && c.ok) out.push_back(peer);
    }
  };
  const auto flows = [&] {
    for (std::uint32_t n = c.count(kMaxEntries); c.ok && n > 0; --n) {
      const AgentId peer = c.u32();
      c.align(8);
      c.skip(8 * 4 + 1);  // flow[3], weight, active
      if (c.ok) out.push_back(peer);
    }
  };
  links(true);   // links
  links(false);  // initial_links: the initial graph, no bond now
  flows();       // flows
  flows();       // copies
  for (std::uint32_t n = c.count(kMaxEntries); c.ok && n > 0; --n) {  // asking
    const AgentId peer = c.u32();
    if (c.ok) out.push_back(peer);
  }
  if (!c.ok) out.clear();
  return out;
}

// Whether the sample names agent `id` among its links, the flows and copies it carries, or the
// peers it asks.
bool mentioned(const dds::IContentFilter::SerializedPayload& payload, AgentId id) {
  const std::vector<AgentId> ids = mentioned_ids(payload.data, payload.length);
  return std::find(ids.begin(), ids.end(), id) != ids.end();
}

class RosterFilter final : public dds::IContentFilter {
 public:
  RosterFilter(RosterExpression expr, RosterFilterFactory& factory)
      : expr_(std::move(expr)), factory_(factory) {}
  bool evaluate(const SerializedPayload& payload, const FilterSampleInfo&,
                const GUID_t& reader) const override {
    if (payload.data == nullptr || payload.length < kRosterIdOffset + 4) return false;
    const unsigned char* d = payload.data;
    const bool little = (d[1] & 1) != 0;  // CDR_LE / PL_CDR_LE
    const auto id = static_cast<AgentId>(read_uint(d, kRosterIdOffset, 4, little));
    if (!in_ranges(expr_.ranges, id)) {
      if (std::memcmp(reader.guidPrefix.value, factory_.local.data(), factory_.local.size()) != 0)
        return false;  // a peer's reader, evaluated by our writer: not ours to count
      StrangerTally& tally = factory_.tally;
      std::lock_guard<std::mutex> lock(tally.mu);
      ++tally.samples;
      if (tally.ids.size() < StrangerTally::kMaxIds) tally.ids.insert(id);
      return false;
    }
    if (id == expr_.self) return false;
    const PlaceSlot& slot = factory_.local_place();
    std::lock_guard<std::mutex> lock(slot.mu);
    const PlaceFilter& place = slot.place;
    if (place.near.empty()) return true;
    factory_.judged_on_arrival.fetch_add(1, std::memory_order_relaxed);
    if (in_ranges(place.names, id)) return true;
    if (payload.length < kPositionOffset + 24) return false;
    const Vec3 q = read_vec3(d, kConsensusOffset, little),
               p = read_vec3(d, kPositionOffset, little);
    if (std::any_of(place.near.begin(), place.near.end(),
                    [&](const Reach& r) { return r.contains(r.space == 'q' ? q : p); }))
      return true;
    // A bond, whatever the place.
    return expr_.self != 0 && mentioned(payload, expr_.self);
  }
  const RosterExpression& expression() const { return expr_; }

 private:
  const RosterExpression expr_;
  RosterFilterFactory& factory_;  // its tally and place (evaluate is const to Fast DDS only)
};

}  // namespace

RosterFilterFactory::ReturnCode_t RosterFilterFactory::create_content_filter(
    const char*, const char*, const dds::TopicDataType*, const char* expression,
    const ParameterSeq& params, dds::IContentFilter*& filter) {
  // The place is the factory's (set_local_place): a filter takes no parameters.
  if (params.length() != 0) return ReturnCode_t::RETCODE_BAD_PARAMETER;
  if (filter != nullptr) {
    // The expression (the roster) is made once, with the reader's topic, and never changes.
    const auto* mine = static_cast<RosterFilter*>(filter);  // this factory makes no other kind
    if (expression != nullptr && parse_roster_filter(expression) != mine->expression())
      return ReturnCode_t::RETCODE_UNSUPPORTED;
    return ReturnCode_t::RETCODE_OK;
  }
  auto expr = parse_roster_filter(expression ? expression : "");
  if (!expr) return ReturnCode_t::RETCODE_BAD_PARAMETER;
  filter = new RosterFilter(std::move(*expr), *this);
  return ReturnCode_t::RETCODE_OK;
}

void RosterFilterFactory::set_local_place(PlaceFilter place) {
  std::lock_guard<std::mutex> lock(local_place_.mu);
  local_place_.place = std::move(place);
}

RosterFilterFactory::ReturnCode_t RosterFilterFactory::delete_content_filter(
    const char*, dds::IContentFilter* filter) {
  delete static_cast<RosterFilter*>(filter);  // this factory makes no other kind
  return ReturnCode_t::RETCODE_OK;
}

std::string roster_filter(std::vector<AgentId> roster, AgentId self) {
  std::sort(roster.begin(), roster.end());
  roster.erase(std::unique(roster.begin(), roster.end()), roster.end());
  std::string expr;
  for (std::size_t i = 0; i < roster.size();) {
    std::size_t j = i;
    while (j + 1 < roster.size() && roster[j + 1] == roster[j] + 1) ++j;
    if (!expr.empty()) expr += ",";
    expr += std::to_string(roster[i]);
    if (j > i) expr += "-" + std::to_string(roster[j]);
    i = j + 1;
  }
  if (self != 0) expr += ";self=" + std::to_string(self);
  return expr;
}

bool serialized_mentions(const unsigned char* data, std::size_t length, AgentId id) {
  const std::vector<AgentId> ids = mentioned_ids(data, length);
  return std::find(ids.begin(), ids.end(), id) != ids.end();
}

std::optional<RosterExpression> parse_roster_filter(const std::string& text) {
  RosterExpression out;
  const std::size_t semi = text.find(';');
  const std::string expr = text.substr(0, semi);
  std::size_t pos = 0;
  const auto number = [](const std::string& s, std::size_t& at, std::uint64_t max,
                         std::uint64_t& out_v) {
    std::size_t end = at;
    while (end < s.size() && end - at < 10 && std::isdigit(static_cast<unsigned char>(s[end])))
      ++end;
    if (end == at) return false;
    const unsigned long long v = std::stoull(s.substr(at, end - at));
    if (v > max) return false;
    out_v = v;
    at = end;
    return true;
  };
  constexpr std::uint64_t kMaxId = std::numeric_limits<AgentId>::max();
  while (pos < expr.size()) {
    std::uint64_t lo = 0;
    if (!number(expr, pos, kMaxId, lo)) return std::nullopt;
    std::uint64_t hi = lo;
    if (pos < expr.size() && expr[pos] == '-') {
      ++pos;
      if (!number(expr, pos, kMaxId, hi) || hi < lo) return std::nullopt;
    }
    out.ranges.emplace_back(static_cast<AgentId>(lo), static_cast<AgentId>(hi));
    if (pos < expr.size() && expr[pos++] != ',') return std::nullopt;
    if (pos == expr.size() && expr.back() == ',') return std::nullopt;
  }
  if (out.ranges.empty()) return std::nullopt;
  // ";self=ID", at most once.
  if (semi != std::string::npos) {
    const std::string opt = text.substr(semi + 1);
    std::size_t p = 5;
    std::uint64_t v = 0;
    if (opt.rfind("self=", 0) != 0 || !number(opt, p, kMaxId, v) || p != opt.size() || v == 0)
      return std::nullopt;
    out.self = static_cast<AgentId>(v);
  }
  return out;
}

}  // namespace qswarm
