#pragma once

#include <cstdint>
#include <vector>

#include "common/view/foxglove_protocol.hpp"

namespace qswarm {

// The channels the view advertises. The record's streams come from the channel catalogue
// (common/record/channels.hpp), so a live session shows the topics and schemas run.mcap holds;
// the page's own channel is added before them.
enum ViewChannelId : std::uint32_t {
  kViewChannel = 1,    // /swarm/view: the page's frames, batched per frame (json)
  kSampleChannel = 2,  // /swarm/agents: records.AgentSample (protobuf)
  kGraphChannel = 3,   // /swarm/graph: records.GraphSnapshot (protobuf)
  kEventChannel = 4,   // /swarm/events: records.Event (protobuf)
  kSceneChannel = 5,   // /swarm/scene: foxglove.SceneUpdate (json), one per graph snapshot
};

std::vector<FoxgloveChannel> view_channels();

}  // namespace qswarm
