#include "common/view/replay.hpp"

#include <google/protobuf/util/json_util.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "common/record/json_writer.hpp"
#include "common/record/record_file.hpp"
#include "common/record/run_dir.hpp"
#include "common/scenario/scenario.hpp"
#include "common/view/view_model.hpp"

namespace qswarm {

ReplayRun load_replay(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw ReplayError(dir.string() + ": no such run directory");
  ReplayRun run;
  const RunDir run_dir(dir);
  const fs::path scenario = run_dir.scenario();
  if (!fs::exists(scenario, ec))
    throw ReplayError(scenario.string() + ": missing (not a run directory?)");
  try {
    const RunConfig rc = load_scenario(scenario.string());
    run.run_info = run_info_json(rc);
    run.scene = SceneSettings::of(rc);
  } catch (const std::exception& e) {
    throw ReplayError(scenario.string() + ": " + e.what());
  }
  const fs::path records = run_dir.records();
  try {
    RecordFileReader in(records);
    records::Record r;
    for (RecordFileReader::Next got; (got = in.next(r)) != RecordFileReader::Next::kEnd;) {
      if (got != RecordFileReader::Next::kRecord) {
        run.note = in.problem();
        break;
      }
      run.records.push_back(std::move(r));
      r.Clear();
      // A run's record is a file of its own: nothing else bounds it, so stop at 8 GiB of memory.
      if (run.records.size() >= 40'000'000) {
        run.note = records.filename().string() + " is cut at 40 million records";
        break;
      }
    }
  } catch (const RecordFileError& e) {
    throw ReplayError(e.what());
  }
  if (run.records.empty())
    throw ReplayError(records.string() + ": no records (the run recorded nothing)" +
                      (run.note.empty() ? std::string() : "; " + run.note));
  const fs::path summary = run_dir.summary();
  std::ifstream s;
  if (fs::is_regular_file(summary, ec)) s.open(summary);  // never a FIFO: it would block
  if (s) {
    std::stringstream text;
    text << s.rdbuf();
    records::Summary sum;
    google::protobuf::util::JsonParseOptions opt;
    opt.ignore_unknown_fields = true;
    if (google::protobuf::util::JsonStringToMessage(text.str(), &sum, opt).ok()) {
      run.summary = std::move(sum);
    } else if (run.note.empty()) {
      run.note = summary.filename().string() + " cannot be read";
    }
  } else if (run.note.empty()) {
    run.note = "the run has no " + summary.filename().string() + " (it was cut short)";
  }
  return run;
}

ReplayPlayback::ReplayPlayback(const ReplayRun& run, double speed) : run_(run), speed_(speed) {
  for (const records::Record& r : run.records)
    duration_s_ = std::max(duration_s_, record_time_s(r));
}

double ReplayPlayback::now_s(double wall_s) const {
  if (!playing_ || !started_) return t_s_;
  return std::min(duration_s_, anchor_t_s_ + (wall_s - anchor_wall_s_) * speed_);
}

ViewBatch ReplayPlayback::advance(double wall_s, bool& reset) {
  if (!started_) {
    started_ = true;
    anchor_wall_s_ = wall_s;
    anchor_t_s_ = t_s_;
  }
  t_s_ = now_s(wall_s);
  reset = reset_;
  reset_ = false;
  // Through a feed with room for the whole run, so a jump carries every snapshot and event that
  // the charts and the event list need.
  ViewFeed feed(
      {4096, std::numeric_limits<std::size_t>::max(), std::numeric_limits<std::size_t>::max()});
  while (cursor_ < run_.records.size() && record_time_s(run_.records[cursor_]) <= t_s_) {
    const records::Record& r = run_.records[cursor_++];
    feed.on_record(r, 0);
  }
  ViewBatch b = feed.take();
  if (cursor_ >= run_.records.size()) {
    if (run_.summary && !summary_sent_) {
      b.summary = run_.summary;
      summary_sent_ = true;
    }
    if (playing_) {
      playing_ = false;  // at the end: paused there
      t_s_ = duration_s_;
    }
  }
  return b;
}

std::string ReplayPlayback::control(const view::ClientOp& op, double wall_s) {
  const std::string& a = op.action();
  t_s_ = now_s(wall_s);
  anchor_wall_s_ = wall_s;
  anchor_t_s_ = t_s_;
  if (a == "play") {
    if (cursor_ >= run_.records.size()) {  // at the end: from the start again
      t_s_ = anchor_t_s_ = 0.0;
      cursor_ = 0;
      reset_ = true;
      summary_sent_ = false;
    }
    playing_ = true;
  } else if (a == "pause") {
    playing_ = false;
  } else if (a == "seek") {
    if (!op.has_t_s() || !std::isfinite(op.t_s()) || op.t_s() < 0.0)
      return "seek needs t, a time in seconds from 0";
    const double t = std::min(op.t_s(), duration_s_);
    if (t < t_s_) {  // back: the view forgets and replays from the start up to t
      cursor_ = 0;
      reset_ = true;
      summary_sent_ = false;
    }
    t_s_ = anchor_t_s_ = t;
  } else if (a == "speed") {
    if (!op.has_speed() || !std::isfinite(op.speed()) || op.speed() <= 0.0 ||
        op.speed() > kMaxSpeed)
      return "speed needs a number above 0 and at most 1000";
    speed_ = op.speed();
  } else {
    return "unknown action '" + a.substr(0, 40) + "' (play, pause, seek, speed)";
  }
  return "";
}

std::string ReplayPlayback::state_json() const {
  std::string out;
  JsonWriter w(out);
  w.raw("{").key("t").num(t_s_, 3).raw(",").key("duration").num(duration_s_, 3).raw(",");
  w.key("playing").boolean(playing_).raw(",").key("speed").sig(speed_).raw(",");
  w.key("note").str(run_.note).raw("}");
  return out;
}

}  // namespace qswarm
