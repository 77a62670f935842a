#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "common/record/convergence.hpp"
#include "common/record/graph_metrics.hpp"
#include "common/record/presence.hpp"
#include "common/record/record_sinks.hpp"
#include "common/record/run_dir.hpp"
#include "common/record/separation.hpp"
#include "common/record/summary.hpp"
#include "common/scenario/run_config.hpp"
#include "common/transport/state_message.hpp"
#include "proto/records.pb.h"

namespace qswarm {

// Everything the supervisor records, fed with samples and wall time: no DDS, no clock of its own,
// so tests drive it. It composes presence (who is here), graph metrics, the convergence judgement,
// the record's files and the summary. Time is the swarm's simulated clock (the newest running
// sample's stamp), carried forward by the wall clock at the run's time scale while no sample
// arrives, so departures are judged in the same time domain as the agents judge them.
class Recorder {
 public:
  // Hosts recorded per agent (restarts elsewhere), beyond which a changing host is not followed.
  static constexpr std::size_t kMaxHostsPerAgent = 16;
  Recorder(RunConfig rc, RunDir dir, double time_scale);

  void on_sample(const StateMessage& m, std::int64_t recv_wall_ns);
  // Other runs heard on this run's domain (their samples were refused): each is an event once,
  // and the summary counts their samples.
  void note_foreign_runs(const std::set<std::uint64_t>& runs, std::uint64_t samples);
  // Ids outside the run whose samples DDS's roster filter dropped before they arrived: each noted
  // once, as a stranger whose samples did arrive would be.
  void note_strangers(const std::set<AgentId>& ids);
  // Agents whose samples `reporter` (an agent; 0: the supervisor's own transport) found forged,
  // with SuspectKind bits: each agent and kind is an event once, and the summary lists who
  // noticed. Two writers at once keep the run from converging.
  void note_suspects(const std::map<AgentId, std::uint8_t>& suspects, AgentId reporter);
  // Lines for the supervisor's log since the last call (forgeries first noticed).
  std::vector<std::string> take_notes();
  // `n` more samples arrived than the supervisor could hold: said once in the record's events and
  // the log, counted in the summary.
  void note_unrecorded(std::uint64_t n);
  // Periodic work (departures, fault windows, graph snapshots, convergence); call every few tens
  // of ms.
  void tick(std::int64_t now_wall_ns);

  // Shows the record to `observer` as it is written, and the summary at the end (nullptr: none).
  // Not owned; it must outlive the recorder or be unset first.
  void set_observer(RunObserver* observer) { sinks_.set_observer(observer); }

  double time_s() const { return t_s_; }
  // The agents agreed, every expected one was there, and no agent's samples were forged.
  bool converged() const { return judge_.converged() && tally_.impersonated().empty(); }
  // Why the run is over ("converged", "agreed without agent 5", "duration"), or "" while it goes
  // on.
  std::string end_reason_if_over() const;
  bool duration_reached() const { return t_s_ >= rc_.judge.duration_s; }
  std::string progress_line() const;
  std::uint32_t departures() const { return tally_.departures; }
  int edges_now() const { return last_ ? last_->edges_size() : 0; }
  // Writes the end event and summary.json and flushes every file; returns the summary for people.
  std::string finish(const std::string& end_reason, double wall_time_s);
  const records::Summary& summary() const { return summary_; }
  // Whether every file of the record was written completely; else the first that failed.
  bool complete() const { return sinks_.ok(); }
  const std::string& failed_file() const { return sinks_.failed_file(); }

 private:
  void event(const std::string& kind, AgentId agent, const std::string& detail);
  void depart(AgentId id, const std::string& why);
  void record_graph(const records::GraphSnapshot& g);
  void snapshot();          // the swarm now, from the latest samples; checks convergence
  void initial_snapshot();  // the swarm at t = 0, from q(0) and each agent's initial links
  double swarm_time_at(std::int64_t wall_ns) const;
  // Law W_MSR: its condition on this snapshot (sets g's robust), timed and told in events.
  void judge_resilience(records::GraphSnapshot& g, const std::vector<AgentId>& ids);
  std::string missing_text() const;
  std::string elsewhere_text() const;
  std::string impersonated_text() const;
  std::string outliers_text() const;
  // Its formation slot about the centre (zero for an agent the scenario does not list).
  Vec3 offset_of(AgentId id) const;

  RunConfig rc_;
  // The F the run's law claims to keep honest agents in their box against (-1: no such claim).
  int hull_f_;
  RunDir dir_;
  double time_scale_;
  RecordSinks sinks_;
  Presence presence_;
  ConvergenceJudge judge_;
  RunTally tally_;
  SeparationMonitor separation_;
  double t_s_ = 0.0;
  std::int64_t t_wall_ns_ = 0;  // wall time when t_s_ last advanced
  double next_snapshot_s_ = 0.0;
  std::optional<records::GraphSnapshot> first_full_, last_;
  SpectrumMemo spectrum_;  // the snapshots' graph, decomposed again only when it changes
  std::vector<FaultPlan::Event> timeline_;
  size_t next_timeline_ = 0;
  std::map<AgentId, double> killed_at_;  // planned kill time, until the departure is seen
  std::set<std::uint64_t> foreign_runs_;
  std::set<AgentId> implausible_;
  std::set<AgentId> hosts_capped_;  // on kMaxHostsPerAgent hosts already: no more followed
  std::vector<std::string> notes_;
  // W-MSR's condition: the graph robustness was last decided for (ids, and edges as id pairs),
  // and what the condition was at the last snapshot.
  std::vector<AgentId> robust_ids_;
  std::vector<std::pair<AgentId, AgentId>> robust_edges_;
  bool robust_ = true, robust_known_ = false;
  bool degree_short_ = false, not_robust_ = false;
  double resilience_t_s_ = -1.0;
  // How far beyond the avoidance filter's distance a neighbour may be and still hold a held agent
  // off its slot (the filter settles at its distance; tracking adds centimetres).
  static constexpr double kHeldReachM = 0.25;
  records::Summary summary_;
};

}  // namespace qswarm
