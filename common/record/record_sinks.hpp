#pragma once

#include <fstream>
#include <string>

#include "common/core/math.hpp"
#include "common/record/mcap_sink.hpp"
#include "common/record/run_dir.hpp"
#include "common/record/run_observer.hpp"
#include "common/transport/state_message.hpp"
#include "proto/records.pb.h"

namespace qswarm {

// The run record's files: telemetry.csv, graph.csv, events.csv (for people and plots),
// records.pb (length-delimited Record messages, for programs) and run.mcap (the same records and a
// 3D scene per graph snapshot, for viewers). Every write is checked: the first file that could not
// be written is remembered, so that a run never reports success over a record that is not
// complete.
class RecordSinks {
 public:
  RecordSinks(const RunDir& dir, SceneSettings scene);
  void sample(const StateMessage& m, double age_ms);
  void graph(const records::GraphSnapshot& g);
  void event(double t_s, const std::string& kind, std::uint32_t agent, const std::string& detail);
  // Flushes every file; returns whether everything written so far reached the files.
  bool flush();
  // Flushes every file and ends run.mcap (its summary and footer): the record is whole only after
  // this. Returns whether everything reached the files.
  bool close();
  bool ok() const { return failed_.empty(); }
  // Marks `path` as not written (a file the caller writes itself, like summary.json).
  void fail(const std::string& path) {
    if (failed_.empty()) failed_ = path;
  }
  // Shows every record to `observer` as it is written (nullptr: none). Not owned.
  void set_observer(RunObserver* observer) { observer_ = observer; }
  RunObserver* observer() const { return observer_; }
  // The first file that failed ("" if none).
  const std::string& failed_file() const { return failed_; }

 private:
  void write_record(const records::Record& r, std::int64_t published_wall_ns = 0);
  void check(std::ofstream& f, const std::filesystem::path& path);
  RunDir dir_;
  std::ofstream telemetry_, graph_, events_, records_;
  McapSink mcap_;
  std::string failed_;
  RunObserver* observer_ = nullptr;
};

}  // namespace qswarm
