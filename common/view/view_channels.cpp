#include "common/view/view_channels.hpp"

#include <string>

#include "common/record/channels.hpp"

namespace qswarm {

std::vector<FoxgloveChannel> view_channels() {
  std::vector<FoxgloveChannel> out = {
      {kViewChannel, "/swarm/view", "json", "qswarm.view.Frame",
       R"({"type":"object","description":"the quadswarm page's frames: a snapshot, then changes"})",
       "jsonschema"}};
  const std::pair<ViewChannelId, Stream> streams[] = {{kSampleChannel, Stream::kAgentSamples},
                                                      {kGraphChannel, Stream::kGraph},
                                                      {kEventChannel, Stream::kEvents},
                                                      {kSceneChannel, Stream::kScene}};
  for (const auto& [id, stream] : streams) {
    const ChannelInfo& c = channel_info(stream);
    // Foxglove's advertise carries a binary schema (a FileDescriptorSet) in base64, text as is.
    const bool binary = c.schema_encoding == "protobuf";
    out.push_back(
        {id, std::string(c.topic), std::string(c.message_encoding), std::string(c.schema_name),
         binary ? base64_encode(c.schema) : std::string(c.schema), std::string(c.schema_encoding)});
  }
  return out;
}

}  // namespace qswarm
