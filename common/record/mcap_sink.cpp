#include "common/record/mcap_sink.hpp"

#include <cmath>

namespace qswarm {

McapSink::McapSink(SceneSettings scene) : scene_(std::move(scene)) {}

std::uint64_t McapSink::log_time_ns(double t_s) {
  if (!std::isfinite(t_s) || t_s <= 0.0) return 0;
  if (t_s >= 1.8e10) return std::uint64_t{18'000'000'000} * 1'000'000'000;  // 570 years: saturate
  return static_cast<std::uint64_t>(std::llround(t_s * 1e9));
}

bool McapSink::open(const std::filesystem::path& path) {
  if (!writer_.open(path)) return false;
  for (const ChannelInfo& c : channel_catalogue()) {
    const std::uint16_t schema = writer_.add_schema(c.schema_name, c.schema_encoding, c.schema);
    channels_[static_cast<std::size_t>(c.stream)] =
        writer_.add_channel(schema, c.topic, c.message_encoding);
  }
  return writer_.ok();
}

void McapSink::put(Stream s, double t_s, const std::string& payload) {
  const auto i = static_cast<std::size_t>(s);
  if (writer_.write(channels_[i], log_time_ns(t_s), payload)) ++counts_[i];
}

void McapSink::write(const records::Record& r) {
  switch (r.body_case()) {
    case records::Record::kSample:
      scene_.on_sample(r.sample());
      r.sample().SerializeToString(&buffer_);
      put(Stream::kAgentSamples, r.sample().stamp_s(), buffer_);
      break;
    case records::Record::kGraph:
      r.graph().SerializeToString(&buffer_);
      put(Stream::kGraph, r.graph().t_s(), buffer_);
      put(Stream::kScene, r.graph().t_s(), scene_.scene_json(r.graph()));
      break;
    case records::Record::kEvent:
      scene_.on_event(r.event());
      r.event().SerializeToString(&buffer_);
      put(Stream::kEvents, r.event().t_s(), buffer_);
      break;
    case records::Record::BODY_NOT_SET:
      break;
  }
}

bool McapSink::close() { return writer_.close(); }

}  // namespace qswarm
