#include "common/record/channels.hpp"

#include "common/record/scene.hpp"
#include "proto/records_descriptor.hpp"

namespace qswarm {

const std::array<ChannelInfo, kStreamCount>& channel_catalogue() {
  static const std::array<ChannelInfo, kStreamCount> catalogue = [] {
    const std::string_view protos = records::records_descriptor_set();
    return std::array<ChannelInfo, kStreamCount>{{
        {Stream::kAgentSamples, "/swarm/agents", "protobuf", "qswarm.records.AgentSample",
         "protobuf", protos},
        {Stream::kGraph, "/swarm/graph", "protobuf", "qswarm.records.GraphSnapshot", "protobuf",
         protos},
        {Stream::kEvents, "/swarm/events", "protobuf", "qswarm.records.Event", "protobuf", protos},
        {Stream::kScene, "/swarm/scene", "json", "foxglove.SceneUpdate", "jsonschema",
         scene_update_json_schema()},
    }};
  }();
  return catalogue;
}

}  // namespace qswarm
