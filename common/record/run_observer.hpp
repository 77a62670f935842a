#pragma once

#include <cstdint>

#include "proto/records.pb.h"

namespace qswarm {

// Something that watches the record as it is written (the live view). The recorder calls it on
// its record path, under the supervisor's lock: an implementation copies what it needs into a
// bounded buffer of its own and returns at once. It never blocks on a client, never throws, and
// nothing it does reaches an agent. Without an observer the record path pays one null check.
class RunObserver {
 public:
  virtual ~RunObserver() = default;
  // A record as it goes to records.pb (an agent sample, a graph snapshot, an event).
  // `published_wall_ns` is a sample's CLOCK_REALTIME at publication (0 for other records), so a
  // viewer can measure its latency from the agent.
  virtual void on_record(const records::Record& r, std::int64_t published_wall_ns) noexcept = 0;
  // The run's summary, once it is written: the end state.
  virtual void on_summary(const records::Summary& s) noexcept = 0;
};

}  // namespace qswarm
