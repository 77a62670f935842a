#include "common/view/view_feed.hpp"

#include <utility>

namespace qswarm {

ViewFeed::ViewFeed(ViewLimits limits) : limits_(limits) {}

void ViewFeed::on_record(const records::Record& r, std::int64_t published_wall_ns) noexcept {
  try {
    std::lock_guard<std::mutex> lock(mu_);
    ++counts_.records;
    if (r.has_sample()) {
      auto it = samples_.find(r.sample().id());
      if (it == samples_.end()) {
        if (samples_.size() >= limits_.max_agents) {
          ++counts_.dropped;
          return;
        }
        it = samples_.emplace(r.sample().id(), ViewSample{}).first;
      }
      it->second.sample = r.sample();
      it->second.published_wall_ns = published_wall_ns;
    } else if (r.has_graph()) {
      if (graphs_.size() >= limits_.max_graphs) {
        graphs_.pop_front();
        ++counts_.dropped;
      }
      graphs_.push_back(r.graph());
    } else if (r.has_event()) {
      if (events_.size() >= limits_.max_events) {
        events_.pop_front();
        ++counts_.dropped;
      }
      events_.push_back(r.event());
    }
  } catch (...) {  // out of memory: the view loses this record, the record path goes on
  }
}

void ViewFeed::on_summary(const records::Summary& s) noexcept {
  try {
    std::lock_guard<std::mutex> lock(mu_);
    summary_ = s;
  } catch (...) {
  }
}

ViewBatch ViewFeed::take() {
  ViewBatch b;
  std::map<std::uint32_t, ViewSample> samples;
  std::deque<records::GraphSnapshot> graphs;
  std::deque<records::Event> events;
  {
    // Swaps under the lock; the copies into the batch happen outside it.
    std::lock_guard<std::mutex> lock(mu_);
    samples.swap(samples_);
    graphs.swap(graphs_);
    events.swap(events_);
    b.summary = std::move(summary_);
    summary_.reset();
  }
  b.samples.reserve(samples.size());
  for (auto& [id, s] : samples) b.samples.push_back(std::move(s));
  b.graphs.assign(std::make_move_iterator(graphs.begin()), std::make_move_iterator(graphs.end()));
  b.events.assign(std::make_move_iterator(events.begin()), std::make_move_iterator(events.end()));
  return b;
}

ViewFeed::Counts ViewFeed::counts() const {
  std::lock_guard<std::mutex> lock(mu_);
  return counts_;
}

}  // namespace qswarm
