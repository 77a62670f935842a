#include "common/transport/dds_names.hpp"

#include <cstdio>

#include "common/transport/interest.hpp"

namespace qswarm::dds_names {

namespace {
constexpr const char* kPrefix = "qswarm-";
constexpr int kRunIdDigits = 16;

std::string stream_partition(const char* stream, std::uint64_t run_id) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%s%s-%0*llx", kPrefix, stream, kRunIdDigits,
                static_cast<unsigned long long>(run_id));
  return buf;
}
}  // namespace

std::string state_topic_of(const std::string& name) {
  return std::string(kStateTopic) + "/" + name;
}

std::string run_partition(std::uint64_t run_id) { return stream_partition(kRunStream, run_id); }

std::string record_partition(std::uint64_t run_id) {
  return stream_partition(kRecordStream, run_id);
}

std::string any_run_partition(const char* stream) { return std::string(kPrefix) + stream + "-*"; }

std::string one_run_pattern(const char* stream) {
  std::string p = std::string(kPrefix) + stream + "-";
  for (int i = 0; i < kRunIdDigits; ++i) p += "[0-9a-f]";
  return p;
}

std::string bound_partition(const std::string& stream_partition, AgentId id) {
  return stream_partition + "/" + agent_partition(id);
}

std::optional<AgentId> agent_of_bound_partition(const std::string& partition) {
  std::size_t at = 0;
  for (const char* stream : {kRunStream, kRecordStream}) {
    const std::string head = std::string(kPrefix) + stream + "-";
    if (partition.compare(0, head.size(), head) == 0) at = head.size();
  }
  const std::size_t digits = kRunIdDigits;
  if (at == 0 || partition.size() < at + digits + 1 || partition[at + digits] != '/') return {};
  for (std::size_t i = at; i < at + digits; ++i) {
    const char c = partition[i];
    if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return {};
  }
  return agent_of_partition(partition.substr(at + digits + 1));
}

}  // namespace qswarm::dds_names
