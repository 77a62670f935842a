#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "common/scenario/run_config.hpp"
#include "common/view/view_feed.hpp"

namespace qswarm {

// What the page needs to know of a run before any sample: its name, mode, law, agents (start,
// formation slot), the initial average and the tolerance. JSON, built once.
std::string run_info_json(const RunConfig& rc);

// The view's picture of the run, on the server's thread: every agent's newest sample and whether
// it is here, the newest graph, the history of the graph's metrics (lambda_2, disagreement,
// drift, smallest separation), the events and the end state. It turns batches from the feed into
// the page's JSON frames, and into a snapshot for a page that connects late (or a replay that
// jumps). Bounded: the metric history thins itself (every other point) past kMaxHistory, events
// keep the first kMaxEvents / 2 and the newest.
class ViewModel {
 public:
  explicit ViewModel(std::string run_info);
  void reset();  // forget the run's progress (a replay seeking backwards)
  void apply(const ViewBatch& b);
  // The change a batch made, for pages already holding a snapshot. `now_wall_ns` is when the
  // frame leaves (CLOCK_REALTIME), so a page can measure latency from the newest sample's
  // publication to its screen.
  // `replay` is the playback state's JSON ("null" for a live run).
  std::string frame_json(const ViewBatch& b, std::int64_t now_wall_ns,
                         const std::string& replay = "null") const;
  // Everything a new page needs. `replay` is the playback state's JSON ("null" for a live run).
  std::string snapshot_json(const std::string& replay = "null") const;

  double time_s() const { return t_s_; }
  std::size_t agents() const { return agents_.size(); }
  std::size_t history_size() const { return history_.size(); }
  bool ended() const { return summary_json_.has_value(); }

  static constexpr std::size_t kMaxHistory = 8192;
  static constexpr std::size_t kMaxEvents = 2048;

 private:
  struct Agent {
    records::AgentSample sample;
    bool present = true;
  };
  struct Metric {
    double t_s, lambda2, disagreement_m, drift_m, min_separation_m;
  };
  std::string run_info_;
  std::map<std::uint32_t, Agent> agents_;
  std::optional<records::GraphSnapshot> graph_;
  std::vector<Metric> history_;
  std::size_t history_stride_ = 1;  // keep every n-th metric once thinned
  std::size_t history_seen_ = 0;
  std::vector<records::Event> events_;
  std::optional<std::string> summary_json_;
  double t_s_ = 0.0;
};

}  // namespace qswarm
