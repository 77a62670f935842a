#include "common/dds/writer_registry.hpp"

#include <spdlog/spdlog.h>

#include <cstring>

#include "common/transport/dds_names.hpp"

namespace qswarm {

namespace frtps = eprosima::fastrtps::rtps;

bool is_partition_pattern(const std::string& partition) {
  return partition.find_first_of("*?[") != std::string::npos;
}

WriterId WriterRegistry::id_of(const frtps::GUID_t& guid) {
  WriterId w;
  std::memcpy(w.bytes.data(), guid.guidPrefix.value, 12);
  std::memcpy(w.bytes.data() + 12, guid.entityId.value, 4);
  return w;
}

std::size_t WriterRegistry::Hash::operator()(const WriterId& w) const {
  return static_cast<std::size_t>(w.hash());
}

WriterRegistry::Binding WriterRegistry::binding(const WriterId& writer) const {
  std::lock_guard<std::mutex> lock(mu_);
  const auto it = writers_.find(writer);
  return it == writers_.end() ? Binding{} : it->second;
}

int WriterRegistry::participants_known() const {
  std::lock_guard<std::mutex> lock(mu_);
  return static_cast<int>(participants_.size());
}

void WriterRegistry::on_participant_discovery(eprosima::fastdds::dds::DomainParticipant*,
                                              frtps::ParticipantDiscoveryInfo&& info) {
  std::array<std::uint8_t, 12> prefix;
  std::memcpy(prefix.data(), info.info.m_guid.guidPrefix.value, prefix.size());
  std::lock_guard<std::mutex> lock(mu_);
  switch (info.status) {
    case frtps::ParticipantDiscoveryInfo::DISCOVERED_PARTICIPANT:
      participants_.insert(prefix);
      break;
    case frtps::ParticipantDiscoveryInfo::REMOVED_PARTICIPANT:
    case frtps::ParticipantDiscoveryInfo::DROPPED_PARTICIPANT:
      participants_.erase(prefix);
      break;
    default:
      break;
  }
}

void WriterRegistry::on_publisher_discovery(eprosima::fastdds::dds::DomainParticipant*,
                                            frtps::WriterDiscoveryInfo&& info) {
  try {
    const std::string topic = info.info.topicName().to_string();
    if (topic != dds_names::kStateTopic && topic != dds_names::kRecordTopic) return;
    const WriterId w = id_of(info.info.guid());
    std::lock_guard<std::mutex> lock(mu_);
    if (info.status == frtps::WriterDiscoveryInfo::REMOVED_WRITER) {
      writers_.erase(w);
      return;
    }
    std::set<AgentId> named;
    bool pattern = false;
    for (const std::string& p : info.info.m_qos.m_partition.getNames()) {
      if (const std::optional<AgentId> id = dds_names::agent_of_bound_partition(p))
        named.insert(*id);
      pattern = pattern || is_partition_pattern(p);
    }
    auto [it, fresh] = writers_.try_emplace(w);
    Binding& b = it->second;
    if (fresh) {
      b.known = true;
      b.named = named;
      b.pattern = pattern;
      if (named.size() == 1 && !pattern) b.agent = *named.begin();
      return;
    }
    if (pattern && !b.pattern) {  // refused from now on; the readers say so when they refuse
      b.pattern = true;
      b.agent.reset();
    }
    if (named != b.named && !b.changed) {
      b.changed = true;
      b.agent.reset();
      spdlog::warn(
          "dds: writer {} on {} changed the agent partitions it publishes into: its samples are "
          "refused from now on",
          w.str(), topic);
    }
  } catch (const std::exception& e) {
    spdlog::error("dds: writer discovery listener caught: {}", e.what());
  }
}

}  // namespace qswarm
