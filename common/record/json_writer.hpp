#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace qswarm {

// Appends JSON to a string: the project's one hand-written JSON (the live view's frames, the MCAP
// scene), built many times a second for up to 512 agents, so numbers are written with a fixed,
// short precision and nothing is parsed back. Strings are escaped and made valid UTF-8 (event
// details and names carry text from people and the network: a byte that is not UTF-8 becomes
// U+FFFD, since a text frame that is not UTF-8 ends a viewer's session); non-finite numbers become
// null. Messages with a schema of their own (summary.json, `swarm inspect --json`) are protobuf's
// JSON instead (proto_util.hpp's to_json).
class JsonWriter {
 public:
  explicit JsonWriter(std::string& out) : out_(out) {}
  JsonWriter& raw(std::string_view s) {
    out_ += s;
    return *this;
  }
  JsonWriter& key(std::string_view k);  // "k":
  JsonWriter& str(std::string_view text);
  JsonWriter& num(double v, int decimals = 4);
  JsonWriter& sig(double v);  // six significant digits (metrics that shrink to 1e-8)
  JsonWriter& integer(std::int64_t v);
  JsonWriter& boolean(bool b) { return raw(b ? "true" : "false"); }

 private:
  std::string& out_;
};

}  // namespace qswarm
