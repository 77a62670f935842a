#include "common/dds/roster_filter.hpp"

#include <fastdds/dds/topic/IContentFilter.hpp>

#include <algorithm>
#include <cctype>
#include <limits>

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

class RosterFilter final : public dds::IContentFilter {
 public:
  RosterFilter(RosterExpression expr, StrangerTally& tally)
      : expr_(std::move(expr)), tally_(tally) {}
  bool evaluate(const SerializedPayload& payload, const FilterSampleInfo&,
                const GUID_t&) const override {
    if (payload.data == nullptr || payload.length < kRosterIdOffset + 4) return false;
    const unsigned char* d = payload.data;
    const bool little = (d[1] & 1) != 0;  // CDR_LE / PL_CDR_LE
    const auto id = static_cast<AgentId>(read_uint(d, kRosterIdOffset, 4, little));
    bool known = false;
    for (const auto& [lo, hi] : expr_.ranges) known |= id >= lo && id <= hi;
    if (!known) {
      std::lock_guard<std::mutex> lock(tally_.mu);
      ++tally_.samples;
      if (tally_.ids.size() < StrangerTally::kMaxIds) tally_.ids.insert(id);
      return false;
    }
    return id != expr_.self;
  }

 private:
  RosterExpression expr_;
  StrangerTally& tally_;
};

}  // namespace

RosterFilterFactory::ReturnCode_t RosterFilterFactory::create_content_filter(
    const char*, const char*, const dds::TopicDataType*, const char* expression,
    const ParameterSeq&, dds::IContentFilter*& filter) {
  auto expr = parse_roster_filter(expression ? expression : "");
  if (!expr) return ReturnCode_t::RETCODE_BAD_PARAMETER;
  // Made once, with the reader's topic: the project never changes a filter's expression (Fast DDS
  // would swap the filter while its receive threads evaluate it).
  if (filter != nullptr) return ReturnCode_t::RETCODE_UNSUPPORTED;
  filter = new RosterFilter(std::move(*expr), tally);
  return ReturnCode_t::RETCODE_OK;
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
