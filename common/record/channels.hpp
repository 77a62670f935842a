#pragma once

#include <array>
#include <cstdint>
#include <string_view>

namespace qswarm {

// The streams a run publishes to viewers: one MCAP channel each in run.mcap, one advertised channel
// each in a Foxglove WebSocket session. This catalogue is the one place that names them and their
// schemas, so a recorded file and a live session show the same topics.
enum class Stream : std::uint8_t {
  kAgentSamples = 0,  // qswarm.records.AgentSample (protobuf), stamped with the agent's stamp_s
  kGraph = 1,         // qswarm.records.GraphSnapshot (protobuf), every 0.1 s of simulated time
  kEvents = 2,        // qswarm.records.Event (protobuf): joins, departures, faults, the verdict
  kScene = 3,         // foxglove.SceneUpdate (JSON): agents, links, agreement point, slots
};
inline constexpr std::size_t kStreamCount = 4;

struct ChannelInfo {
  Stream stream;
  std::string_view topic;             // "/swarm/agents", ...
  std::string_view message_encoding;  // MCAP / Foxglove message encoding: "protobuf" or "json"
  std::string_view schema_name;       // the fully qualified message name ("foxglove.SceneUpdate")
  std::string_view schema_encoding;   // "protobuf" (a FileDescriptorSet) or "jsonschema"
  std::string_view schema;            // the schema's bytes (binary for protobuf: not text)
};

// Every stream, in the order of Stream's values (catalogue()[int(s)] is stream s).
const std::array<ChannelInfo, kStreamCount>& channel_catalogue();
inline const ChannelInfo& channel_info(Stream s) {
  return channel_catalogue()[static_cast<std::size_t>(s)];
}

}  // namespace qswarm
