#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "proto/view.pb.h"

namespace qswarm {

// Foxglove's WebSocket protocol (foxglove.websocket.v1; foxglove.sdk.v1 is the same wire for what
// a read-only server uses), the parts a server that only publishes needs: serverInfo, advertise
// with schemas, status, subscribe/unsubscribe from the client, and binary message frames. Pure:
// strings in, strings out; the server does the sockets.

inline constexpr const char* kFoxgloveSubprotocol = "foxglove.websocket.v1";
inline constexpr const char* kFoxgloveSdkSubprotocol = "foxglove.sdk.v1";

// The sub-protocol the server speaks with a client that offered `offered` (the
// Sec-WebSocket-Protocol header: a comma-separated list), or "" if none of ours is in it.
std::string choose_subprotocol(std::string_view offered);

struct FoxgloveChannel {
  std::uint32_t id = 0;
  std::string topic;
  std::string encoding;         // "protobuf", "json"
  std::string schema_name;      // e.g. "qswarm.records.AgentSample"
  std::string schema;           // as sent: base64 FileDescriptorSet for protobuf, text for json
  std::string schema_encoding;  // "protobuf", "jsonschema"
};

std::string base64_encode(std::string_view bytes);
std::string server_info_json(const std::string& name, const std::string& session_id);
std::string advertise_json(const std::vector<FoxgloveChannel>& channels);
// level 0 info, 1 warning, 2 error.
std::string status_json(int level, const std::string& message);
// Binary message data: opcode 0x01, u32 subscription id, u64 log time (ns), then the payload, all
// little-endian.
std::string message_frame(std::uint32_t subscription_id, std::uint64_t log_time_ns,
                          std::string_view payload);

// One connection's side of the protocol: which channels the client subscribed to, under which of
// its ids. Every client frame is judged here; what is refused says why.
class FoxgloveSession {
 public:
  explicit FoxgloveSession(const std::vector<FoxgloveChannel>& channels,
                           std::size_t max_subscriptions = 64)
      : channels_(channels), max_subscriptions_(max_subscriptions) {}

  struct Outcome {
    bool malformed = false;                  // not JSON, not an object, a field of the wrong type
    std::vector<std::string> refusals;       // what the client asked for and did not get, and why
    std::vector<std::uint32_t> subscribed;   // channel ids newly subscribed
    std::optional<view::ClientOp> playback;  // a qswarmPlayback op (the server decides)
  };
  Outcome handle_text(std::string_view text);

  // The client's subscription id for a channel, if it subscribed.
  std::optional<std::uint32_t> subscription(std::uint32_t channel_id) const;
  std::size_t subscriptions() const { return by_channel_.size(); }

 private:
  const std::vector<FoxgloveChannel>& channels_;
  std::size_t max_subscriptions_;
  std::map<std::uint32_t, std::uint32_t> by_channel_;  // channel id -> subscription id
  std::map<std::uint32_t, std::uint32_t> by_id_;       // subscription id -> channel id
};

}  // namespace qswarm
