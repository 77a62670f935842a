#include "common/dds/roster_filter.hpp"

#include <fastdds/dds/topic/IContentFilter.hpp>

#include <algorithm>
#include <cctype>
#include <limits>

namespace qswarm {

namespace dds = eprosima::fastdds::dds;

namespace {

class RosterFilter final : public dds::IContentFilter {
 public:
  RosterFilter(std::vector<std::pair<AgentId, AgentId>> ranges, StrangerTally& tally)
      : ranges_(std::move(ranges)), tally_(tally) {}
  bool evaluate(const SerializedPayload& payload, const FilterSampleInfo&,
                const GUID_t&) const override {
    if (payload.data == nullptr || payload.length < 8) return false;
    const unsigned char* d = payload.data;
    const bool little = (d[1] & 1) != 0;  // CDR_LE / PL_CDR_LE
    const AgentId id =
        little ? AgentId{d[4]} | AgentId{d[5]} << 8 | AgentId{d[6]} << 16 | AgentId{d[7]} << 24
               : AgentId{d[7]} | AgentId{d[6]} << 8 | AgentId{d[5]} << 16 | AgentId{d[4]} << 24;
    for (const auto& [lo, hi] : ranges_)
      if (id >= lo && id <= hi) return true;
    std::lock_guard<std::mutex> lock(tally_.mu);
    ++tally_.samples;
    if (tally_.ids.size() < StrangerTally::kMaxIds) tally_.ids.insert(id);
    return false;
  }

 private:
  std::vector<std::pair<AgentId, AgentId>> ranges_;
  StrangerTally& tally_;
};

}  // namespace

RosterFilterFactory::ReturnCode_t RosterFilterFactory::create_content_filter(
    const char*, const char*, const dds::TopicDataType*, const char* expression,
    const ParameterSeq&, dds::IContentFilter*& filter) {
  auto ranges = parse_roster_filter(expression ? expression : "");
  if (!ranges) return ReturnCode_t::RETCODE_BAD_PARAMETER;
  delete static_cast<RosterFilter*>(filter);  // an expression update replaces the previous one
  filter = new RosterFilter(std::move(*ranges), tally);
  return ReturnCode_t::RETCODE_OK;
}

RosterFilterFactory::ReturnCode_t RosterFilterFactory::delete_content_filter(
    const char*, dds::IContentFilter* filter) {
  delete static_cast<RosterFilter*>(filter);  // this factory makes no other kind
  return ReturnCode_t::RETCODE_OK;
}

std::string roster_filter(std::vector<AgentId> roster) {
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
  return expr;
}

std::optional<std::vector<std::pair<AgentId, AgentId>>> parse_roster_filter(
    const std::string& expr) {
  std::vector<std::pair<AgentId, AgentId>> ranges;
  std::size_t pos = 0;
  const auto number = [&](AgentId& out) {
    std::size_t end = pos;
    while (end < expr.size() && end - pos < 10 &&
           std::isdigit(static_cast<unsigned char>(expr[end])))
      ++end;
    if (end == pos) return false;
    const unsigned long long v = std::stoull(expr.substr(pos, end - pos));
    if (v > std::numeric_limits<AgentId>::max()) return false;
    out = static_cast<AgentId>(v);
    pos = end;
    return true;
  };
  while (pos < expr.size()) {
    AgentId lo = 0;
    if (!number(lo)) return std::nullopt;
    AgentId hi = lo;
    if (pos < expr.size() && expr[pos] == '-') {
      ++pos;
      if (!number(hi) || hi < lo) return std::nullopt;
    }
    ranges.emplace_back(lo, hi);
    if (pos < expr.size() && expr[pos++] != ',') return std::nullopt;
    if (pos == expr.size() && expr.back() == ',') return std::nullopt;
  }
  if (ranges.empty()) return std::nullopt;
  return ranges;
}

}  // namespace qswarm
