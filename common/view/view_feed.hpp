#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <vector>

#include "common/record/run_observer.hpp"
#include "proto/records.pb.h"

namespace qswarm {

// How much the feed holds between two frames of the view. Every buffer is bounded: a server that
// falls behind loses the oldest graphs and events (counted), never the record path's time.
struct ViewLimits {
  std::size_t max_agents = 1024;  // distinct ids whose newest sample is held (a run has <= 512)
  std::size_t max_graphs = 64;    // graph snapshots (10 a simulated second)
  std::size_t max_events = 256;
};

// An agent's newest sample and the wall time (CLOCK_REALTIME, ns) its agent published it.
struct ViewSample {
  records::AgentSample sample;
  std::int64_t published_wall_ns = 0;
};

// What arrived since the previous take: each agent's newest sample (older ones of the same frame
// are superseded, so a frame carries one sample per agent whatever the agents' rate), every graph
// snapshot and event, and the summary once the run is over.
struct ViewBatch {
  std::vector<ViewSample> samples;
  std::vector<records::GraphSnapshot> graphs;
  std::vector<records::Event> events;
  std::optional<records::Summary> summary;
  bool empty() const { return samples.empty() && graphs.empty() && events.empty() && !summary; }
};

// The record path's side of the live view: a RunObserver that copies each record into bounded
// buffers under its own short lock and returns. The view's server thread takes what arrived, once
// a frame. Nothing here waits on a client.
class ViewFeed : public RunObserver {
 public:
  explicit ViewFeed(ViewLimits limits = {});
  void on_record(const records::Record& r, std::int64_t published_wall_ns) noexcept override;
  void on_summary(const records::Summary& s) noexcept override;
  ViewBatch take();

  struct Counts {
    std::uint64_t records = 0;  // records seen
    std::uint64_t dropped = 0;  // graphs, events or new agents' samples dropped for the bounds
  };
  Counts counts() const;

 private:
  ViewLimits limits_;
  mutable std::mutex mu_;
  std::map<std::uint32_t, ViewSample> samples_;
  std::deque<records::GraphSnapshot> graphs_;
  std::deque<records::Event> events_;
  std::optional<records::Summary> summary_;
  Counts counts_;
};

}  // namespace qswarm
