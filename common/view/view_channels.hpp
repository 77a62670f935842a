#pragma once

#include <string>
#include <vector>

#include <google/protobuf/descriptor.h>

#include "common/view/foxglove_protocol.hpp"

namespace qswarm {

// The channels the view advertises. The page subscribes to kViewChannel (its own JSON frames,
// batched per frame); Foxglove and Lichtblick plot the record's protobuf messages.
enum ViewChannelId : std::uint32_t {
  kViewChannel = 1,    // /qswarm/view: the page's frames (json)
  kSampleChannel = 2,  // /qswarm/agent_samples: records.AgentSample (protobuf)
  kGraphChannel = 3,   // /qswarm/graph: records.GraphSnapshot (protobuf)
  kEventChannel = 4,   // /qswarm/events: records.Event (protobuf)
};

// A message type's file and every file it imports, as a binary FileDescriptorSet (what Foxglove
// and MCAP expect as a protobuf schema).
std::string descriptor_set(const google::protobuf::Descriptor* d);

std::vector<FoxgloveChannel> view_channels();

}  // namespace qswarm
