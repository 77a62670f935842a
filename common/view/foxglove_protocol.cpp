#include "common/view/foxglove_protocol.hpp"

#include <google/protobuf/util/json_util.h>

#include <algorithm>

#include "common/record/json_writer.hpp"

namespace qswarm {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

void put_le(std::string& out, std::uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out += static_cast<char>((v >> (8 * i)) & 0xff);
}

}  // namespace

std::string choose_subprotocol(std::string_view offered) {
  // Newer Foxglove clients offer foxglove.sdk.v1 (and may offer both); Lichtblick offers only
  // foxglove.websocket.v1. The first of ours in the client's list wins.
  while (!offered.empty()) {
    const std::size_t comma = offered.find(',');
    const std::string_view p = trim(offered.substr(0, comma));
    if (p == kFoxgloveSubprotocol || p == kFoxgloveSdkSubprotocol) return std::string(p);
    if (comma == std::string_view::npos) break;
    offered.remove_prefix(comma + 1);
  }
  return "";
}

std::string base64_encode(std::string_view bytes) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const std::uint32_t v = static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[i])) << 16 |
                            static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[i + 1]))
                                << 8 |
                            static_cast<unsigned char>(bytes[i + 2]);
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += kAlphabet[(v >> 6) & 63];
    out += kAlphabet[v & 63];
  }
  if (i < bytes.size()) {
    std::uint32_t v = static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[i])) << 16;
    if (i + 1 < bytes.size())
      v |= static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[i + 1])) << 8;
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

std::string server_info_json(const std::string& name, const std::string& session_id) {
  std::string out;
  JsonWriter w(out);
  // No capability: the view publishes and answers subscriptions, nothing more (no client
  // publishing, parameters or services: nothing a client sends reaches the swarm).
  w.raw("{").key("op").str("serverInfo").raw(",").key("name").str(name).raw(",");
  w.key("capabilities").raw("[],").key("metadata").raw("{},").key("sessionId").str(session_id);
  w.raw("}");
  return out;
}

std::string advertise_json(const std::vector<FoxgloveChannel>& channels) {
  std::string out;
  JsonWriter w(out);
  w.raw("{").key("op").str("advertise").raw(",").key("channels").raw("[");
  for (std::size_t i = 0; i < channels.size(); ++i) {
    const FoxgloveChannel& c = channels[i];
    if (i) w.raw(",");
    w.raw("{").key("id").integer(c.id).raw(",").key("topic").str(c.topic).raw(",");
    w.key("encoding").str(c.encoding).raw(",").key("schemaName").str(c.schema_name).raw(",");
    w.key("schema").str(c.schema).raw(",").key("schemaEncoding").str(c.schema_encoding).raw("}");
  }
  w.raw("]}");
  return out;
}

std::string status_json(int level, const std::string& message) {
  std::string out;
  JsonWriter w(out);
  w.raw("{").key("op").str("status").raw(",").key("level").integer(level).raw(",");
  w.key("message").str(message).raw("}");
  return out;
}

std::string message_frame(std::uint32_t subscription_id, std::uint64_t log_time_ns,
                          std::string_view payload) {
  std::string out;
  out.reserve(13 + payload.size());
  out += '\x01';
  put_le(out, subscription_id, 4);
  put_le(out, log_time_ns, 8);
  out.append(payload);
  return out;
}

FoxgloveSession::Outcome FoxgloveSession::handle_text(std::string_view text) {
  Outcome o;
  view::ClientOp op;
  google::protobuf::util::JsonParseOptions opt;
  opt.ignore_unknown_fields = true;  // other fields of ops we do not serve
  if (!google::protobuf::util::JsonStringToMessage(
           google::protobuf::StringPiece(text.data(), text.size()), &op, opt)
           .ok() ||
      op.op().empty()) {
    o.malformed = true;
    return o;
  }
  if (op.op() == "subscribe") {
    for (const view::Subscription& s : op.subscriptions()) {
      const bool known =
          std::any_of(channels_.begin(), channels_.end(),
                      [&](const FoxgloveChannel& c) { return c.id == s.channel_id(); });
      if (!known) {
        o.refusals.push_back("subscribe: no channel " + std::to_string(s.channel_id()));
      } else if (by_id_.count(s.id())) {
        o.refusals.push_back("subscribe: subscription id " + std::to_string(s.id()) + " is in use");
      } else if (by_channel_.count(s.channel_id())) {
        o.refusals.push_back("subscribe: channel " + std::to_string(s.channel_id()) +
                             " is already subscribed");
      } else if (by_channel_.size() >= max_subscriptions_) {
        o.refusals.push_back("subscribe: at most " + std::to_string(max_subscriptions_) +
                             " subscriptions");
      } else {
        by_id_[s.id()] = s.channel_id();
        by_channel_[s.channel_id()] = s.id();
        o.subscribed.push_back(s.channel_id());
      }
    }
  } else if (op.op() == "unsubscribe") {
    for (const std::uint32_t id : op.subscription_ids()) {
      const auto it = by_id_.find(id);
      if (it == by_id_.end()) {
        o.refusals.push_back("unsubscribe: no subscription " + std::to_string(id));
        continue;
      }
      by_channel_.erase(it->second);
      by_id_.erase(it);
    }
  } else if (op.op() == "qswarmPlayback") {
    o.playback = op;
  } else {
    o.refusals.push_back("op '" + op.op().substr(0, 40) +
                         "' is not served: this server only publishes");
  }
  return o;
}

std::optional<std::uint32_t> FoxgloveSession::subscription(std::uint32_t channel_id) const {
  const auto it = by_channel_.find(channel_id);
  if (it == by_channel_.end()) return std::nullopt;
  return it->second;
}

}  // namespace qswarm
