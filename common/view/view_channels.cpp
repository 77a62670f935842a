#include "common/view/view_channels.hpp"

#include <google/protobuf/descriptor.pb.h>

#include <set>

#include "proto/records.pb.h"

namespace qswarm {
namespace {

// Dependencies first, each file once, as protoc --include_imports writes them.
void add_file(const google::protobuf::FileDescriptor* f, std::set<std::string>& seen,
              google::protobuf::FileDescriptorSet& set) {
  if (!seen.insert(f->name()).second) return;
  for (int i = 0; i < f->dependency_count(); ++i) add_file(f->dependency(i), seen, set);
  f->CopyTo(set.add_file());
}

FoxgloveChannel protobuf_channel(std::uint32_t id, const std::string& topic,
                                 const google::protobuf::Descriptor* d) {
  return {id, topic, "protobuf", d->full_name(), base64_encode(descriptor_set(d)), "protobuf"};
}

}  // namespace

std::string descriptor_set(const google::protobuf::Descriptor* d) {
  google::protobuf::FileDescriptorSet set;
  std::set<std::string> seen;
  add_file(d->file(), seen, set);
  return set.SerializeAsString();
}

std::vector<FoxgloveChannel> view_channels() {
  return {
      {kViewChannel, "/qswarm/view", "json", "qswarm.view.Frame",
       R"({"type":"object","description":"the quadswarm page's frames: a snapshot, then changes"})",
       "jsonschema"},
      protobuf_channel(kSampleChannel, "/qswarm/agent_samples", records::AgentSample::descriptor()),
      protobuf_channel(kGraphChannel, "/qswarm/graph", records::GraphSnapshot::descriptor()),
      protobuf_channel(kEventChannel, "/qswarm/events", records::Event::descriptor()),
  };
}

}  // namespace qswarm
