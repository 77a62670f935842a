#include "common/record/recorder.hpp"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <tuple>

#include "common/core/law_registry.hpp"
#include "common/record/graph_metrics.hpp"

#include "common/scenario/proto_util.hpp"
#include "common/transport/stamp_slack.hpp"

namespace qswarm {
namespace {

std::vector<AgentId> ids_of(const RunConfig& rc) {
  std::vector<AgentId> ids;
  for (const AgentSpec& a : rc.agents) ids.push_back(a.id);
  return ids;
}

}  // namespace

Recorder::Recorder(RunConfig rc, RunDir dir, double time_scale)
    : rc_(std::move(rc)),
      hull_f_(honest_hull_f(rc_.agent.law)),
      dir_(std::move(dir)),
      time_scale_(time_scale),
      sinks_(dir_, SceneSettings::of(rc_)),
      presence_(ids_of(rc_), rc_.plan.presence_timeout_s, rc_.plan.record_every),
      judge_(rc_.judge.tolerance_m, rc_.judge.hold_s, rc_.agent.neighbor_timeout_s,
             find_law(rc_.agent.law.law).claims.exact_average ? rc_.judge.tolerance_m : -1.0,
             rc_.faults, std::max(0, hull_f_)),
      separation_(rc_.agent.avoidance.safe_distance_m),
      timeline_(rc_.faults.timeline()) {
  tally_.held = rc_.held_agents();
  if (hull_f_ >= 0) {
    records::ResilienceOverTime r;
    r.set_f(static_cast<std::uint32_t>(hull_f_));
    r.set_min_degree(static_cast<std::uint32_t>(rc_.agents.size()));
    r.set_first_degree_short_s(-1.0);
    r.set_first_not_robust_s(-1.0);
    if (rc_.agents.size() <= static_cast<std::size_t>(kMaxExactRobustness))
      r.set_robust_always(true);
    tally_.resilience = r;
  }
}

void Recorder::event(const std::string& kind, AgentId agent, const std::string& detail) {
  sinks_.event(t_s_, kind, agent, detail);
}

double Recorder::swarm_time_at(std::int64_t wall_ns) const {
  if (t_wall_ns_ == 0) return t_s_;
  return t_s_ + std::max(0.0, static_cast<double>(wall_ns - t_wall_ns_) * 1e-9 * time_scale_);
}

void Recorder::on_sample(const StateMessage& m, std::int64_t recv_wall_ns) {
  // A stamp far ahead of the swarm's clock (as carried forward by the wall clock) cannot be one of
  // the run's agents' ticks: recording it would move the run's clock, end the run at once and fill
  // graph.csv. Refused, counted, and said once per agent.
  if (rc_.spec(m.view.id) && m.stamp_s > swarm_time_at(recv_wall_ns) + kStampSlackS) {
    ++tally_.implausible_samples;
    if (implausible_.insert(m.view.id).second) {
      char buf[160];
      std::snprintf(buf, sizeof buf,
                    "sample stamped %.3f s while the swarm's clock is at %.3f s: refused",
                    m.stamp_s, swarm_time_at(recv_wall_ns));
      event("implausible_sample", m.view.id, buf);
    }
    return;
  }
  if (m.phase == Phase::kRunning && m.stamp_s > t_s_ && rc_.spec(m.view.id)) {
    t_s_ = m.stamp_s;
    t_wall_ns_ = recv_wall_ns;
  }
  const AgentId id = m.view.id;
  switch (presence_.on_sample(m, swarm_time_at(recv_wall_ns))) {
    case Presence::Change::kStranger:
      // Not an agent of this scenario (e.g. a stray participant on the domain): note it once and
      // keep it out of the swarm's graph, agreement and summary.
      event("unknown_agent", id, "sample from an agent not in the scenario");
      return;
    case Presence::Change::kStrangerAgain:
      return;
    case Presence::Change::kJoin:
      ++tally_.joins;
      event("join", id, "first sample");
      break;
    case Presence::Change::kRejoin:
      ++tally_.joins;
      event("rejoin", id, "heard again after departure");
      break;
    case Presence::Change::kDepart:
      ++tally_.departures;
      separation_.forget(id);
      event("depart", id, "agent stopped");
      break;
    case Presence::Change::kNone:
      break;
  }
  tally_.fault_counts[{id, m.incarnation}] = m.faults;
  if (!m.host.empty()) {
    std::vector<std::string>& hosts = tally_.hosts[id];
    // A host it flew on before counts again (a restart back on it); a sender whose host changes
    // more often than restarts do is told once and not followed.
    if (hosts.empty() || hosts.back() != m.host) {
      if (hosts.size() < kMaxHostsPerAgent) {
        hosts.push_back(m.host);
        event("host", id, "flies on " + m.host);
      } else if (hosts_capped_.insert(id).second) {
        event("host", id,
              "on more than " + std::to_string(kMaxHostsPerAgent) +
                  " hosts: those after are not recorded");
      }
    }
  }
  // What the agent's transport found forged: the recorder does not hear the agents' stream.
  if (!m.suspects.empty()) {
    std::map<AgentId, std::uint8_t> suspects;
    for (const Suspect& s : m.suspects) suspects[s.id] |= s.kinds;
    note_suspects(suspects, id);
  }
  // Strangers the agent's transport turned away: the recorder does not hear the agents' stream.
  for (const AgentId s : m.strangers)
    if (presence_.note_stranger(s))
      event("unknown_agent", s,
            "samples from an agent not in the scenario, heard by agent " + std::to_string(id));
  const double age_ms = m.wall_ns > 0 ? static_cast<double>(recv_wall_ns - m.wall_ns) / 1e6 : 0.0;
  if (m.wall_ns > 0) tally_.ages_ms.push_back(age_ms);
  sinks_.sample(m, age_ms);
  // A running sample's position is for its stamp; a waiting (or restarting) agent's stamp is not on
  // the swarm's clock yet: its position is for now.
  if (m.phase != Phase::kStopping)
    separation_.on_sample(id, m.p_W, m.v_W,
                          m.phase == Phase::kRunning ? m.stamp_s : swarm_time_at(recv_wall_ns));
  // The initial graph, once every agent of the scenario has reported the links its law started
  // with (view seq >= 1), however late its first samples reached us.
  if (!first_full_ && m.phase == Phase::kRunning && m.view.seq >= 1) {
    bool all = true;
    for (const auto& [aid, t] : presence_.tracks()) all &= t.seen && t.last.view.seq >= 1;
    if (all) initial_snapshot();
  }
}

void Recorder::note_foreign_runs(const std::set<std::uint64_t>& runs, std::uint64_t samples) {
  for (const std::uint64_t id : runs) {
    if (!foreign_runs_.insert(id).second) continue;
    char buf[120];
    std::snprintf(buf, sizeof buf,
                  "another run (id %016llx) shares this domain: its samples are dropped",
                  static_cast<unsigned long long>(id));
    event("foreign_run", 0, buf);
  }
  tally_.foreign_samples = samples;
}

void Recorder::note_strangers(const std::set<AgentId>& ids) {
  for (const AgentId id : ids)
    if (presence_.note_stranger(id))
      event("unknown_agent", id, "sample from an agent not in the scenario");
}

void Recorder::note_suspects(const std::map<AgentId, std::uint8_t>& suspects, AgentId reporter) {
  const std::string by = reporter == 0 ? "the supervisor" : "agent " + std::to_string(reporter);
  for (const auto& [id, kinds] : suspects) {
    // Only the scenario's agents: a report naming others would grow the record without bound.
    if (presence_.tracks().count(id) == 0) continue;
    for (const SuspectKind k : {kTwoWriters, kSequenceJump, kFutureIncarnation, kBoundElsewhere}) {
      if ((kinds & k) == 0) continue;
      const auto [it, fresh] = tally_.forgeries.try_emplace({id, static_cast<std::uint8_t>(k)});
      it->second.noticed_by.insert(reporter);
      if (!fresh) continue;
      it->second.first_t_s = t_s_;
      const std::string detail =
          std::string(suspect_name(k)) + ": " + suspect_text(k) + "; noticed by " + by;
      event("forgery", id, detail);
      notes_.push_back("agent " + std::to_string(id) + " " + detail);
    }
  }
}

void Recorder::note_unrecorded(std::uint64_t n) {
  if (n == 0) return;
  if (tally_.unrecorded == 0) {
    const std::string detail =
        "samples arrive faster than the supervisor records them: those that find its inbox full "
        "are not recorded (counted in the summary as unrecorded, and as gaps)";
    event("supervisor_behind", 0, detail);
    notes_.push_back(detail);
  }
  tally_.unrecorded += n;
}

std::vector<std::string> Recorder::take_notes() {
  std::vector<std::string> out;
  out.swap(notes_);
  return out;
}

void Recorder::depart(AgentId id, const std::string& why) {
  ++tally_.departures;
  separation_.forget(id);
  event("depart", id, why);
  if (auto k = killed_at_.find(id); k != killed_at_.end()) {
    tally_.detect_s.push_back(t_s_ - k->second);
    killed_at_.erase(k);
  }
}

void Recorder::tick(std::int64_t now_wall_ns) {
  // An agent silent past the neighbour timeout on the swarm's clock has departed.
  for (const AgentId id : presence_.expire(swarm_time_at(now_wall_ns)))
    depart(id, "silent past the neighbour timeout");
  // The fault plan's windows, as the swarm's clock passes them.
  while (next_timeline_ < timeline_.size() && timeline_[next_timeline_].t_s <= t_s_) {
    const FaultPlan::Event& e = timeline_[next_timeline_++];
    event(e.kind, e.agent, e.detail);
    ++tally_.fault_events;
    if (e.kind == "kill") killed_at_[e.agent] = e.t_s;
  }
  while (t_s_ >= next_snapshot_s_) {
    snapshot();
    next_snapshot_s_ += 0.1;
  }
}

void Recorder::record_graph(const records::GraphSnapshot& g) { sinks_.graph(g); }

void Recorder::initial_snapshot() {
  std::vector<AgentId> ids;
  Positions q0, p0, offsets;
  for (const auto& [id, a] : presence_.tracks()) {
    ids.push_back(id);
    q0.push_back(a.last.view.q0);
    offsets.push_back(offset_of(id));
    p0.push_back(q0.back() + offsets.back());
  }
  // The swarm at t = 0: the links each agent's law started with, weighed at q(0) by the run's
  // weight policy (an agent whose law started a tick after a peer's saw that peer already moved).
  std::vector<std::vector<std::pair<AgentId, double>>> links(ids.size());
  for (size_t i = 0; i < ids.size(); ++i) {
    for (const auto& [peer, w] : presence_.track(ids[i]).last.initial_links) {
      const auto& tracks = presence_.tracks();
      const auto other = tracks.find(peer);
      if (other == tracks.end()) continue;
      const double d = (q0[i] - other->second.last.view.q0).norm();
      links[i].emplace_back(peer, weight_for_distance(rc_.agent.law.weight, d));
    }
  }
  first_full_ = measure_graph(
      0.0, ids, q0, p0, [&](int i) -> const auto& { return links[static_cast<size_t>(i)]; },
      rc_.initial_average(), offsets);
  record_graph(*first_full_);
  last_ = first_full_;  // so that the live line shows the initial graph too
}

void Recorder::snapshot() {
  std::vector<AgentId> ids;
  Positions q, p, offsets;
  std::vector<double> speed;
  WmsrMeasure wmsr{std::max(0, hull_f_), rc_.judge.tolerance_m, {}};
  for (const auto& [id, a] : presence_.tracks()) {
    if (presence_.running(id)) {
      ids.push_back(id);
      wmsr.q0.push_back(a.last.view.q0);
      q.push_back(a.last.view.q);
      p.push_back(a.last.p_W);
      offsets.push_back(offset_of(id));
      speed.push_back(a.last.v_W.norm());
    }
  }
  // A held agent (its slot too close to another's to reach) is excused from the spread only while
  // another agent actually holds it off: one within the filter's distance plus kHeldReachM. Else it
  // is judged on its slot like everyone (a crawler far from its slot has not arrived).
  std::vector<bool> held(ids.size(), false);
  double held_speed = 0.0;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    if (!tally_.held.count(ids[i])) continue;
    for (std::size_t j = 0; j < ids.size() && !held[i]; ++j)
      held[i] =
          j != i && (p[i] - p[j]).norm() <= rc_.agent.avoidance.filter_distance_m() + kHeldReachM;
    if (held[i]) held_speed = std::max(held_speed, speed[i]);
  }
  last_ = measure_graph(
      t_s_, ids, q, p,
      [&](int i) -> const auto& { return presence_.track(ids[static_cast<size_t>(i)]).last.links; },
      rc_.initial_average(), offsets, held, hull_f_ >= 0 ? &wmsr : nullptr, &spectrum_);
  last_->set_held_speed_mps(held_speed);
  // Judged once the whole swarm has started: a swarm still starting lacks links it will have.
  if (tally_.resilience && first_full_) judge_resilience(*last_, ids);
  record_graph(*last_);
  const ConvergenceJudge::Verdict v = judge_.update(t_s_, *last_, presence_);
  if (v == ConvergenceJudge::Verdict::kNone) return;
  char buf[120];
  std::snprintf(buf, sizeof buf, "disagreement %.3g m, spread %.3g m", last_->disagreement_m(),
                last_->spread_m());
  if (v == ConvergenceJudge::Verdict::kConverged && !converged()) {
    event("agreed_forged", 0, impersonated_text() + "; " + buf);
  } else if (v == ConvergenceJudge::Verdict::kConverged) {
    event("converged", 0, buf);
  } else if (v == ConvergenceJudge::Verdict::kAgreedExceptOutliers) {
    event("agreed_except", 0, outliers_text() + "; " + buf);
  } else if (v == ConvergenceJudge::Verdict::kAgreedElsewhere) {
    event("agreed_elsewhere", 0, elsewhere_text() + "; " + buf);
  } else {
    event("agreed_without", 0, missing_text() + " missing; " + buf);
  }
}

Vec3 Recorder::offset_of(AgentId id) const {
  const AgentSpec* spec = rc_.spec(id);
  return spec ? spec->offset_W : Vec3::Zero();
}

std::string Recorder::missing_text() const {
  std::string ids;
  for (const AgentId id : judge_.missing()) ids += (ids.empty() ? "" : ", ") + std::to_string(id);
  return "agent" + std::string(judge_.missing().size() > 1 ? "s " : " ") + ids;
}

void Recorder::judge_resilience(records::GraphSnapshot& g, const std::vector<AgentId>& ids) {
  records::ResilienceOverTime& r = *tally_.resilience;
  const int f = hull_f_;
  // Each condition is timed from one snapshot to the next, in the state it was in.
  const double dt = resilience_t_s_ < 0.0 ? 0.0 : t_s_ - resilience_t_s_;
  resilience_t_s_ = t_s_;
  r.set_min_degree(std::min(r.min_degree(), g.min_degree()));
  if (degree_short_) r.set_degree_short_s(r.degree_short_s() + dt);
  const bool short_now = g.min_degree() < static_cast<std::uint32_t>(2 * f + 1);
  if (short_now != degree_short_) {
    char buf[160];
    if (short_now) {
      if (r.first_degree_short_s() < 0.0) r.set_first_degree_short_s(t_s_);
      std::snprintf(buf, sizeof buf, "an agent reads %u neighbour%s; %s with F = %d needs %d",
                    g.min_degree(), g.min_degree() == 1 ? "" : "s", rc_.agent.law.law.c_str(), f,
                    2 * f + 1);
    } else {
      std::snprintf(buf, sizeof buf, "every agent reads at least %d neighbours again", 2 * f + 1);
    }
    event(short_now ? "resilience_lost" : "resilience_restored", 0, buf);
    degree_short_ = short_now;
  }
  if (ids.size() > static_cast<std::size_t>(kMaxExactRobustness)) return;
  // Exhaustive, so decided once per distinct graph: the graph changes far less often than it is
  // measured.
  std::vector<std::pair<AgentId, AgentId>> edges;
  for (const records::GraphEdge& e : g.edges()) edges.emplace_back(e.a(), e.b());
  if (!robust_known_ || ids != robust_ids_ || edges != robust_edges_) {
    std::vector<Edge> by_index;
    for (const auto& [a, b] : edges) {
      const auto i = std::find(ids.begin(), ids.end(), a) - ids.begin();
      const auto j = std::find(ids.begin(), ids.end(), b) - ids.begin();
      by_index.push_back({static_cast<int>(i), static_cast<int>(j), 1.0});
    }
    robust_ = is_rs_robust(static_cast<int>(ids.size()), by_index, f + 1, f + 1);
    robust_known_ = true;
    robust_ids_ = ids;
    robust_edges_ = std::move(edges);
    r.set_robustness_checks(r.robustness_checks() + 1);
  }
  g.set_robust(robust_);
  if (not_robust_) r.set_not_robust_s(r.not_robust_s() + dt);
  if (!robust_) r.set_robust_always(false);
  if (robust_ == not_robust_) {  // it changed
    char buf[160];
    if (!robust_) {
      if (r.first_not_robust_s() < 0.0) r.set_first_not_robust_s(t_s_);
      std::snprintf(buf, sizeof buf,
                    "the graph is not (%d, %d)-robust: up to F = %d liars can drag or split the "
                    "others",
                    f + 1, f + 1, f);
    } else {
      std::snprintf(buf, sizeof buf, "the graph is (%d, %d)-robust again", f + 1, f + 1);
    }
    event(robust_ ? "resilience_restored" : "resilience_lost", 0, buf);
    not_robust_ = !robust_;
  }
}

std::string Recorder::outliers_text() const {
  std::string ids;
  for (const AgentId id : judge_.outliers()) ids += (ids.empty() ? "" : ", ") + std::to_string(id);
  std::string text = "agreed except agent" +
                     std::string(judge_.outliers().size() > 1 ? "s " : " ") + ids + " (a liar " +
                     rc_.agent.law.law + " ignored, or an agent cut off)";
  if (judge_.agreed_elsewhere_m() >= 0.0) {
    char buf[120];
    std::snprintf(buf, sizeof buf, ", %.3g m outside the others' initial bounding box",
                  judge_.agreed_elsewhere_m());
    text += buf;
  }
  return text;
}

std::string Recorder::elsewhere_text() const {
  char buf[240];
  std::snprintf(buf, sizeof buf,
                "agreed %.3g m from the initial average, which %s keeps: forged states or "
                "flows?",
                judge_.agreed_elsewhere_m(), rc_.agent.law.law.c_str());
  if (hull_f_ >= 0)
    std::snprintf(buf, sizeof buf,
                  "agreed %.3g m outside the agents' initial bounding box, which %s keeps: more "
                  "than F = %d liars, or too few links?",
                  judge_.agreed_elsewhere_m(), rc_.agent.law.law.c_str(), hull_f_);
  return buf;
}

std::string Recorder::impersonated_text() const {
  const std::vector<AgentId> ids = tally_.impersonated();
  std::string list;
  std::set<AgentId> by;
  for (const AgentId id : ids) {
    list += (list.empty() ? "" : ", ") + std::to_string(id);
    const auto& noticed = tally_.forgeries.at({id, static_cast<std::uint8_t>(kTwoWriters)});
    by.insert(noticed.noticed_by.begin(), noticed.noticed_by.end());
  }
  // Who said so: without security a report is itself a sample anyone could have forged.
  std::string who;
  for (const AgentId r : by)
    who += (who.empty() ? "" : ", ") + (r == 0 ? std::string("the supervisor") : std::to_string(r));
  return "agreed, but the samples of agent" + std::string(ids.size() > 1 ? "s " : " ") + list +
         " came from two writers at once (an impersonator, or a relay of it; noticed by " + who +
         "): not trusted";
}

std::string Recorder::end_reason_if_over() const {
  if (judge_.converged()) return converged() ? "converged" : impersonated_text();
  if (judge_.agreed_without_some()) return "agreed without " + missing_text();
  if (!judge_.outliers().empty()) return outliers_text();
  if (judge_.agreed_elsewhere_m() >= 0.0) return elsewhere_text();
  if (duration_reached()) return "duration";
  return "";
}

std::string Recorder::progress_line() const {
  char buf[200];
  std::snprintf(buf, sizeof buf,
                "t=%7.2f s  agents %zu/%zu  edges %3d  lambda2 %8.4f  disagreement %9.5f m", t_s_,
                presence_.present_count(), rc_.agents.size(), last_ ? last_->edges_size() : 0,
                last_ ? last_->lambda2() : 0.0, last_ ? last_->disagreement_m() : 0.0);
  return buf;
}

std::string Recorder::finish(const std::string& end_reason, double wall_time_s) {
  if (t_s_ >= next_snapshot_s_ || !last_) snapshot();
  if (separation_.measured()) {
    tally_.min_separation_m = separation_.min_m();
    tally_.min_separation_t_s = separation_.min_t_s();
    std::tie(tally_.min_separation_a, tally_.min_separation_b) = separation_.min_pair();
  }
  tally_.separation_violations = separation_.violations();
  summary_ = build_summary(rc_, presence_, judge_, tally_, first_full_, last_,
                           {end_reason, t_s_, wall_time_s, time_scale_});
  event("end", 0, end_reason);
  // The files end before the summary is written, so that a file that could not be completed (a
  // full disk) is in the summary too: never "converged" over a record cut short.
  if (!sinks_.close()) {
    summary_.set_converged(false);
    summary_.set_end_reason(summary_.end_reason() + "; record incomplete: could not write " +
                            std::filesystem::path(sinks_.failed_file()).filename().string());
  }
  if (RunObserver* o = sinks_.observer()) o->on_summary(summary_);
  const std::string json = to_json(summary_);
  if (!dir_.write_summary(json)) sinks_.fail(dir_.summary().string());
  std::string text = summary_text(summary_, rc_, dir_.str());
  if (!sinks_.ok()) text += "RECORD INCOMPLETE: could not write " + sinks_.failed_file() + "\n";
  return text;
}

}  // namespace qswarm
