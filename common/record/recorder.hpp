#pragma once

#include <cstdint>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "common/core/graph.hpp"
#include "common/runtime/link_faults.hpp"
#include "common/runtime/run_config.hpp"
#include "common/transport/state_message.hpp"
#include "proto/records.pb.h"

namespace qswarm {

// Everything the supervisor records, fed with samples and wall time: no DDS, no clock of its own,
// so it can be driven by tests. Writes telemetry.csv, graph.csv, events.csv, records.pb and, at the
// end, summary.json into the run directory.
class Recorder {
 public:
  Recorder(RunConfig rc, std::string run_dir, double time_scale);
  ~Recorder();

  void on_sample(const StateMessage& m, std::int64_t recv_wall_ns);
  // Periodic work (departures, graph snapshots, convergence); call every few tens of ms.
  void tick(std::int64_t now_wall_ns);

  double time_s() const { return t_s_; }
  bool converged() const { return converged_; }
  bool duration_reached() const { return t_s_ >= rc_.duration_s; }
  std::string progress_line() const;
  int edges_now() const { return last_ ? last_->edges_size() : 0; }
  // Writes summary.json and closes the files; returns the human-readable summary.
  std::string finish(const std::string& end_reason, double wall_time_s);
  const records::Summary& summary() const { return summary_; }

 private:
  struct AgentTrack {
    StateMessage first, last;
    bool seen = false;
    bool present = false;
    std::int64_t last_recv_ns = 0;
    std::uint64_t samples = 0, gaps = 0;
    double first_stamp = 0.0;
  };
  void event(const std::string& kind, AgentId agent, const std::string& detail);
  // One graph snapshot (graph.csv row and record) from the given agents, states and links.
  records::GraphSnapshot graph_of(
      double t_s, const std::vector<AgentId>& ids, const Positions& q, const Positions& p,
      const std::function<const std::vector<std::pair<AgentId, double>>&(int)>& links_of);
  void snapshot();          // the swarm now, from the latest samples; checks convergence
  void initial_snapshot();  // the swarm at t = 0, from q(0) and each agent's initial links
  void write_record(const records::Record& r);

  RunConfig rc_;
  std::string dir_;
  double time_scale_;
  std::ofstream telemetry_, graph_, events_, records_;
  std::map<AgentId, AgentTrack> agents_;  // the scenario's agents only
  std::set<AgentId> unknown_;
  std::vector<double> ages_ms_;
  double t_s_ = 0.0;
  double next_snapshot_s_ = 0.0;
  bool converged_ = false;
  double hold_start_s_ = -1.0;
  double converged_at_s_ = -1.0;
  std::uint32_t joins_ = 0, departures_ = 0;
  double min_separation_ = 1e300;
  std::optional<records::GraphSnapshot> first_full_, last_;
  std::vector<FaultPlan::Event> timeline_;
  size_t next_timeline_ = 0;
  std::map<AgentId, double> killed_at_;  // planned kill time, until the departure is seen
  std::vector<double> detect_s_;
  std::uint32_t fault_events_ = 0;
  // Fault counters per agent incarnation (an incarnation's counters only grow).
  std::map<std::pair<AgentId, std::int64_t>, FaultCounters> fault_counts_;
  records::Summary summary_;
};

}  // namespace qswarm
