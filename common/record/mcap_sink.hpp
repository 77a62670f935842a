#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>

#include "common/mcap/writer.hpp"
#include "common/record/channels.hpp"
#include "common/record/scene.hpp"
#include "proto/records.pb.h"

namespace qswarm {

// run.mcap from the record's own stream: every Record the recorder writes to records.pb goes to
// its channel (channels.hpp), and each graph snapshot also becomes a 3D scene. Log times are
// simulated nanoseconds: a sample's stamp, a snapshot's or an event's t_s. The recorder and
// `swarm export` both write through this, so a file rebuilt from records.pb is the same file.
class McapSink {
 public:
  explicit McapSink(SceneSettings scene);

  // Creates the file and writes its header, schemas and channels; false (with error()) if not.
  bool open(const std::filesystem::path& path);
  void write(const records::Record& r);
  // Writes the summary and the footer: the file is complete only after this returned true.
  bool close();

  // Whether the next write() will first write out a chunk (see mcap::Writer::chunk_due).
  bool chunk_due() const { return writer_.chunk_due(); }
  bool ok() const { return writer_.ok(); }
  const std::string& error() const { return writer_.error(); }
  // Messages written per stream (Stream's order).
  const std::array<std::uint64_t, kStreamCount>& counts() const { return counts_; }

  // A time in simulated seconds as a log time (ns); negative or not finite as 0.
  static std::uint64_t log_time_ns(double t_s);

 private:
  void put(Stream s, double t_s, const std::string& payload);

  mcap::Writer writer_;
  SceneBuilder scene_;
  std::array<std::uint16_t, kStreamCount> channels_{};
  std::array<std::uint64_t, kStreamCount> counts_{};
  std::string buffer_;
};

}  // namespace qswarm
