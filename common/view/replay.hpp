#pragma once

#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/record/record_file.hpp"
#include "common/view/view_server.hpp"

namespace qswarm {

// A recorded run as the view replays it: what the page needs to know of the run, every record of
// records.pb in order, and the summary when the run wrote one.
struct ReplayRun {
  std::string run_info;  // run_info_json of scenario.txtpb
  SceneSettings scene;   // its initial average and slots, for the scene channel
  std::vector<records::Record> records;
  std::optional<records::Summary> summary;
  std::string note;  // what is odd about the record (a partial last record, no summary), or ""
};

struct ReplayError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Reads a run directory. Throws ReplayError naming the file and what is wrong with it (missing,
// unreadable, no records).
ReplayRun load_replay(const std::filesystem::path& dir);

// Plays a recorded run into the view as if live, at `speed` simulated seconds per wall second,
// from the first wall time it is asked about. A page may pause, play, seek and change the speed
// (the only control a client has, and only over a replay). It pauses at the end.
class ReplayPlayback : public ViewPlayback {
 public:
  ReplayPlayback(const ReplayRun& run, double speed);
  ViewBatch advance(double wall_s, bool& reset) override;
  std::string control(const view::ClientOp& op, double wall_s) override;
  std::string state_json() const override;
  double duration_s() const { return duration_s_; }
  double time_s() const { return t_s_; }

  static constexpr double kMaxSpeed = 1000.0;

 private:
  double now_s(double wall_s) const;
  const ReplayRun& run_;
  double speed_;
  double duration_s_ = 0.0;
  bool playing_ = true;
  bool started_ = false;
  double anchor_wall_s_ = 0.0, anchor_t_s_ = 0.0;  // playback time anchor_t_s_ at anchor_wall_s_
  double t_s_ = 0.0;
  std::size_t cursor_ = 0;
  bool reset_ = false;
  bool summary_sent_ = false;
};

}  // namespace qswarm
