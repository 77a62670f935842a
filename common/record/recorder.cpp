#include "common/record/recorder.hpp"

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl.h>
#include <google/protobuf/util/json_util.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <sstream>

#include "common/core/graph.hpp"

namespace qswarm {
namespace {

void put(google::protobuf::RepeatedField<double>* f, const Vec3& v) {
  f->Add(v.x());
  f->Add(v.y());
  f->Add(v.z());
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  const std::size_t k = static_cast<std::size_t>(p * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
  return v[k];
}

std::string fmt(const char* f, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, x);
  return buf;
}

}  // namespace

Recorder::Recorder(RunConfig rc, std::string run_dir, double time_scale)
    : rc_(std::move(rc)), dir_(std::move(run_dir)), time_scale_(time_scale) {
  telemetry_.open(dir_ + "/telemetry.csv");
  graph_.open(dir_ + "/graph.csv");
  events_.open(dir_ + "/events.csv");
  records_.open(dir_ + "/records.pb", std::ios::binary);
  if (!telemetry_ || !graph_ || !events_ || !records_) {
    throw std::runtime_error("cannot write the run directory " + dir_);
  }
  telemetry_ << "stamp_s,id,seq,phase,mode,qx,qy,qz,px,py,pz,vx,vy,vz,qw,qxr,qyr,qzr,w1,w2,w3,w4,"
                "total_weight,links,age_ms\n";
  graph_ << "t_s,agents,edges,lambda2,components,disagreement_m,mean_drift_m,min_separation_m,"
            "spread_m,edge_list\n";
  events_ << "t_s,kind,agent,detail\n";
  for (const AgentSpec& a : rc_.agents) agents_[a.id];
  timeline_ = rc_.faults.timeline();
  telemetry_ << std::setprecision(10);
  graph_ << std::setprecision(10);
}

Recorder::~Recorder() = default;

void Recorder::write_record(const records::Record& r) {
  google::protobuf::io::OstreamOutputStream raw(&records_);
  google::protobuf::io::CodedOutputStream out(&raw);
  out.WriteVarint32(static_cast<std::uint32_t>(r.ByteSizeLong()));
  r.SerializeWithCachedSizes(&out);
}

void Recorder::event(const std::string& kind, AgentId agent, const std::string& detail) {
  events_ << t_s_ << ',' << kind << ',' << agent << ",\"" << detail << "\"\n";
  events_.flush();
  records::Record r;
  records::Event* e = r.mutable_event();
  e->set_t_s(t_s_);
  e->set_kind(kind);
  e->set_agent(agent);
  e->set_detail(detail);
  write_record(r);
}

void Recorder::on_sample(const StateMessage& m, std::int64_t recv_ns) {
  const AgentId id = m.view.id;
  auto it = agents_.find(id);
  if (it == agents_.end()) {
    // Not an agent of this scenario (e.g. a stray participant on the domain): note it once and
    // keep it out of the swarm's graph, agreement and summary.
    if (unknown_.insert(id).second)
      event("unknown_agent", id, "sample from an agent not in the scenario");
    return;
  }
  AgentTrack& a = it->second;
  if (m.phase == kRunning) t_s_ = std::max(t_s_, m.stamp_s);
  if (!a.seen) {
    a.seen = true;
    a.first = m;
    a.first_stamp = m.stamp_s;
    ++joins_;
    event("join", id, "first sample");
  } else if (!a.present && m.phase != kStopping) {
    ++joins_;
    event("rejoin", id, "heard again after departure");
  }
  if (a.samples > 0 && m.incarnation == a.last.incarnation && m.seq > a.last.seq + 1) {
    a.gaps += m.seq - a.last.seq - 1;
  }
  if (m.phase == kStopping && a.present) {
    ++departures_;
    event("depart", id, "agent stopped");
  }
  a.present = m.phase != kStopping;
  a.last = m;
  a.last_recv_ns = recv_ns;
  fault_counts_[{id, m.incarnation}] = {m.fault_loss, m.fault_burst, m.fault_cut, m.fault_partition,
                                        m.fault_delayed};
  ++a.samples;
  const double age_ms = m.wall_ns > 0 ? static_cast<double>(recv_ns - m.wall_ns) / 1e6 : 0.0;
  if (m.wall_ns > 0) ages_ms_.push_back(age_ms);

  const Vec3& q = m.view.q;
  const Eigen::Quaterniond& o = m.q_WB;
  telemetry_ << m.stamp_s << ',' << id << ',' << m.seq << ',' << int(m.phase) << ',' << int(m.mode)
             << ',' << q.x() << ',' << q.y() << ',' << q.z() << ',' << m.p_W.x() << ',' << m.p_W.y()
             << ',' << m.p_W.z() << ',' << m.v_W.x() << ',' << m.v_W.y() << ',' << m.v_W.z() << ','
             << o.w() << ',' << o.x() << ',' << o.y() << ',' << o.z() << ',' << m.rotors_radps[0]
             << ',' << m.rotors_radps[1] << ',' << m.rotors_radps[2] << ',' << m.rotors_radps[3]
             << ',' << m.view.total_weight << ',' << m.links.size() << ',' << age_ms << '\n';
  records::Record r;
  records::AgentSample* s = r.mutable_sample();
  s->set_id(id);
  s->set_seq(m.seq);
  s->set_stamp_s(m.stamp_s);
  s->set_age_ms(age_ms);
  put(s->mutable_consensus(), q);
  put(s->mutable_position(), m.p_W);
  put(s->mutable_velocity(), m.v_W);
  s->add_orientation(o.w());
  s->add_orientation(o.x());
  s->add_orientation(o.y());
  s->add_orientation(o.z());
  for (int i = 0; i < 4; ++i) s->add_rotors(m.rotors_radps[i]);
  s->set_mode(static_cast<std::uint32_t>(m.mode));
  write_record(r);
  // The initial graph, once every agent of the scenario has reported the links its law started
  // with (view seq >= 1), however late its first samples reached us.
  if (!first_full_ && m.phase == kRunning && m.view.seq >= 1) {
    bool all = true;
    for (const auto& [aid, t] : agents_) all &= t.seen && t.last.view.seq >= 1;
    if (all) initial_snapshot();
  }
}

void Recorder::tick(std::int64_t now_ns) {
  // An agent silent past the neighbour timeout (in wall time at this time scale) has departed.
  const double timeout_ns = rc_.neighbor_timeout_s / time_scale_ * 1e9;
  for (auto& [id, a] : agents_) {
    if (a.present && a.seen && static_cast<double>(now_ns - a.last_recv_ns) > timeout_ns) {
      a.present = false;
      ++departures_;
      event("depart", id, "silent past the neighbour timeout");
      if (auto k = killed_at_.find(id); k != killed_at_.end()) {
        detect_s_.push_back(t_s_ - k->second);
        killed_at_.erase(k);
      }
    }
  }
  // The fault plan's windows, as the swarm's clock passes them.
  while (next_timeline_ < timeline_.size() && timeline_[next_timeline_].t_s <= t_s_) {
    const FaultPlan::Event& e = timeline_[next_timeline_++];
    event(e.kind, e.agent, e.detail);
    ++fault_events_;
    if (e.kind == "kill") killed_at_[e.agent] = e.t_s;
  }
  while (t_s_ >= next_snapshot_s_) {
    snapshot();
    next_snapshot_s_ += 0.1;
  }
}

records::GraphSnapshot Recorder::graph_of(
    double t_s, const std::vector<AgentId>& ids, const Positions& q, const Positions& p,
    const std::function<const std::vector<std::pair<AgentId, double>>&(int)>& links_of) {
  records::Record r;
  records::GraphSnapshot& g = *r.mutable_graph();
  g.set_t_s(t_s);
  g.set_agents(static_cast<std::uint32_t>(ids.size()));
  const std::vector<Edge> edges = edges_from_links(ids, links_of);
  std::ostringstream list;
  for (const Edge& edge : edges) {
    records::GraphEdge* e = g.add_edges();
    e->set_a(ids[edge.i]);
    e->set_b(ids[edge.j]);
    e->set_weight(edge.weight);
    list << (list.tellp() > 0 ? ";" : "") << ids[edge.i] << '-' << ids[edge.j] << ':'
         << edge.weight;
  }
  const int n = static_cast<int>(ids.size());
  if (n > 0) {
    const Spectrum s = analyze(laplacian(n, edges));
    g.set_lambda2(s.lambda2);
    g.set_components(static_cast<std::uint32_t>(s.components));
    const Vec3 qbar = average(q);
    g.set_disagreement_m(disagreement(q));
    g.set_mean_drift_m((qbar - rc_.initial_average()).norm());
    double min_sep = 1e300;
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j) min_sep = std::min(min_sep, (p[i] - p[j]).norm());
    if (n > 1) {
      g.set_min_separation_m(min_sep);
      min_separation_ = std::min(min_separation_, min_sep);
    }
    double spread = 0.0;
    for (const Vec3& x : p) spread = std::max(spread, (x - qbar).norm());
    g.set_spread_m(spread);
  }
  graph_ << g.t_s() << ',' << g.agents() << ',' << g.edges_size() << ',' << g.lambda2() << ','
         << g.components() << ',' << g.disagreement_m() << ',' << g.mean_drift_m() << ','
         << g.min_separation_m() << ',' << g.spread_m() << ",\"" << list.str() << "\"\n";
  write_record(r);
  return g;
}

void Recorder::initial_snapshot() {
  std::vector<AgentId> ids;
  Positions q0;
  for (const auto& [id, a] : agents_) {
    ids.push_back(id);
    q0.push_back(a.last.view.q0);
  }
  // The swarm at t = 0: the links each agent's law started with, weighed at q(0) by the run's
  // weight policy (an agent whose law started a tick after a peer's saw that peer already moved).
  std::vector<std::vector<std::pair<AgentId, double>>> links(ids.size());
  for (size_t i = 0; i < ids.size(); ++i) {
    for (const auto& [peer, w] : agents_.at(ids[i]).last.initial_links) {
      const auto other = agents_.find(peer);
      if (other == agents_.end()) continue;
      const double d = (q0[i] - other->second.last.view.q0).norm();
      links[i].emplace_back(peer, weight_for_distance(rc_.law.weight, d));
    }
  }
  first_full_ = graph_of(
      0.0, ids, q0, q0, [&](int i) -> const auto& { return links[static_cast<size_t>(i)]; });
  last_ = first_full_;  // so that the live line shows the initial graph too
}

void Recorder::snapshot() {
  std::vector<AgentId> ids;
  Positions q, p;
  for (const auto& [id, a] : agents_) {
    if (a.present && a.last.phase == kRunning) {
      ids.push_back(id);
      q.push_back(a.last.view.q);
      p.push_back(a.last.p_W);
    }
  }
  const records::GraphSnapshot g = graph_of(
      t_s_, ids, q, p, [&](int i) -> const auto& { return agents_.at(ids[i]).last.links; });
  const int n = static_cast<int>(ids.size());
  last_ = g;
  std::size_t joined = 0;
  for (const auto& [id, a] : agents_) joined += a.seen ? 1 : 0;

  // Converged only when every agent the plan says is alive now is back and running (a restarted or
  // late agent must have joined), not before the last planned fault is over, and when they agree.
  bool all_back = joined + rc_.faults.late_join.size() >= rc_.agents.size();
  for (const AgentSpec& spec : rc_.agents) {
    // Agents the plan brings back (a due restart or late join) must be here; an unplanned
    // departure (a crash, an outside SIGKILL) is allowed: the others go on.
    bool due_back = false;
    for (const auto& k : rc_.faults.kill) {
      if (k.agent == spec.id && k.at_s <= t_s_)
        due_back = k.restart_at_s > k.at_s && k.restart_at_s <= t_s_;
    }
    for (const auto& j : rc_.faults.late_join) {
      if (j.agent == spec.id && j.at_s <= t_s_) due_back = true;
    }
    const AgentTrack& tr = agents_.at(spec.id);
    if (due_back && !(tr.present && tr.last.phase == kRunning)) all_back = false;
  }
  const bool agree = n > 0 && all_back && t_s_ >= rc_.faults.last_fault_end_s() &&
                     g.disagreement_m() < rc_.tolerance_m && g.spread_m() < rc_.tolerance_m;
  if (agree) {
    if (hold_start_s_ < 0.0) hold_start_s_ = t_s_;
    if (!converged_ && t_s_ - hold_start_s_ >= rc_.hold_s) {
      converged_ = true;
      converged_at_s_ = hold_start_s_;
      event("converged", 0,
            "disagreement " + fmt("%.3g", g.disagreement_m()) + " m, spread " +
                fmt("%.3g", g.spread_m()) + " m");
    }
  } else {
    hold_start_s_ = -1.0;
  }
}

std::string Recorder::progress_line() const {
  std::size_t present = 0;
  for (const auto& [id, a] : agents_) present += a.present ? 1 : 0;
  char buf[200];
  std::snprintf(buf, sizeof buf,
                "t=%7.2f s  agents %zu/%zu  edges %3d  lambda2 %8.4f  disagreement %9.5f m", t_s_,
                present, rc_.agents.size(), last_ ? last_->edges_size() : 0,
                last_ ? last_->lambda2() : 0.0, last_ ? last_->disagreement_m() : 0.0);
  return buf;
}

std::string Recorder::finish(const std::string& end_reason, double wall_time_s) {
  if (t_s_ >= next_snapshot_s_ || !last_) snapshot();
  records::Summary& s = summary_;
  s.set_scenario(rc_.name);
  s.set_converged(converged_);
  s.set_convergence_time_s(converged_ ? converged_at_s_ : -1.0);
  s.set_end_reason(end_reason);
  s.set_wall_time_s(wall_time_s);
  s.set_duration_s(t_s_);
  s.set_seed(static_cast<std::uint32_t>(rc_.seed));
  s.set_mode(rc_.mode == AgentMode::kQuadcopter ? "quadcopter" : "particle");
  s.set_law(to_string(rc_.law.kind));
  s.set_agents_expected(static_cast<std::uint32_t>(rc_.agents.size()));
  s.set_joins(joins_);
  s.set_departures(departures_);
  s.set_min_separation_m(min_separation_ < 1e299 ? min_separation_ : 0.0);
  put(s.mutable_initial_average(), rc_.initial_average());

  Positions final_q, final_p;
  records::Messages& msg = *s.mutable_messages();
  double rate_sum = 0.0;
  int rate_n = 0;
  for (const auto& [id, a] : agents_) {
    records::AgentSummary* as = s.add_agents();
    as->set_id(id);
    const AgentSpec* spec = rc_.agent(id);
    put(as->mutable_initial_position(), spec ? spec->position_W : a.first.view.q0);
    if (!a.seen) continue;
    put(as->mutable_final_position(), a.last.p_W);
    put(as->mutable_final_consensus(), a.last.view.q);
    as->set_samples(static_cast<std::uint32_t>(a.samples));
    as->set_seq_gaps(static_cast<std::uint32_t>(a.gaps));
    as->set_dropped_by_agent(static_cast<std::uint32_t>(a.last.dropped));
    const double span = a.last.stamp_s - a.first_stamp;
    if (span > 0.0) {
      as->set_rate_hz(static_cast<double>(a.samples - 1) / (span / time_scale_));
      rate_sum += as->rate_hz();
      ++rate_n;
    }
    if (spec) {
      final_q.push_back(a.last.view.q);
      final_p.push_back(a.last.p_W);
    }
    msg.set_published(msg.published() + static_cast<std::uint32_t>(a.last.seq));
    msg.set_received(msg.received() + static_cast<std::uint32_t>(a.samples));
    msg.set_dropped(msg.dropped() + static_cast<std::uint32_t>(a.last.dropped));
    msg.set_seq_gaps(msg.seq_gaps() + static_cast<std::uint32_t>(a.gaps));
  }
  msg.set_age_p50_ms(percentile(ages_ms_, 0.50));
  msg.set_age_p99_ms(percentile(ages_ms_, 0.99));
  msg.set_rate_hz(rate_n ? rate_sum / rate_n : 0.0);
  const Vec3 mean = average(final_q);
  put(s.mutable_final_consensus_mean(), mean);
  s.set_average_drift_m(final_q.empty() ? 0.0 : (mean - rc_.initial_average()).norm());
  double spread = 0.0;
  for (const Vec3& x : final_p) spread = std::max(spread, (x - average(final_p)).norm());
  s.set_max_final_spread_m(spread);
  s.set_final_disagreement_m(final_q.empty() ? 0.0 : disagreement(final_q));
  const auto edges_of = [](const records::GraphSnapshot& g, auto* out) {
    for (const records::GraphEdge& e : g.edges()) {
      google::protobuf::ListValue* l = out->Add();
      l->add_values()->set_number_value(e.a());
      l->add_values()->set_number_value(e.b());
      l->add_values()->set_number_value(e.weight());
    }
  };
  if (first_full_) {
    s.set_lambda2_initial(first_full_->lambda2());
    edges_of(*first_full_, s.mutable_edges_initial());
  }
  if (last_) {
    s.set_lambda2_final(last_->lambda2());
    edges_of(*last_, s.mutable_edges_final());
  }
  records::FaultSummary& fs = *s.mutable_faults();
  FaultCounters total;
  for (const auto& [key, c] : fault_counts_) {
    total.loss += c.loss;
    total.burst += c.burst;
    total.cut += c.cut;
    total.partition += c.partition;
    total.delayed += c.delayed;
  }
  fs.set_loss(static_cast<std::uint32_t>(total.loss));
  fs.set_burst(static_cast<std::uint32_t>(total.burst));
  fs.set_cut(static_cast<std::uint32_t>(total.cut));
  fs.set_partition(static_cast<std::uint32_t>(total.partition));
  fs.set_delayed(static_cast<std::uint32_t>(total.delayed));
  fs.set_dropped(static_cast<std::uint32_t>(total.dropped()));
  for (const auto& k : rc_.faults.kill) {
    if (k.at_s <= t_s_) fs.set_kills(fs.kills() + 1);
    if (k.restart_at_s > k.at_s && k.restart_at_s <= t_s_) fs.set_restarts(fs.restarts() + 1);
  }
  for (const auto& j : rc_.faults.late_join)
    if (j.at_s <= t_s_) fs.set_late_joins(fs.late_joins() + 1);
  fs.set_transport_drop_percent(rc_.faults.transport_drop_percent);
  fs.set_events(fault_events_);
  double detect = 0.0;
  for (double d : detect_s_) detect += d;
  s.set_detect_s(detect_s_.empty() ? -1.0 : detect / static_cast<double>(detect_s_.size()));
  const double last_fault = rc_.faults.last_fault_end_s();
  s.set_last_fault_end_s(last_fault);
  s.set_reconverge_s(converged_ && last_fault > 0.0 ? std::max(0.0, converged_at_s_ - last_fault)
                                                    : -1.0);
  const double avg_norm = rc_.initial_average().norm();
  s.set_average_relative_error(avg_norm > 0 ? s.average_drift_m() / avg_norm : s.average_drift_m());
  event("end", 0, end_reason);

  std::string json;
  google::protobuf::util::JsonPrintOptions opt;
  opt.add_whitespace = true;
  opt.preserve_proto_field_names = true;
  opt.always_print_primitive_fields = true;
  (void)google::protobuf::util::MessageToJsonString(s, &json, opt);
  std::ofstream(dir_ + "/summary.json") << json;
  telemetry_.flush();
  graph_.flush();
  records_.flush();

  std::ostringstream h;
  h << "\n== " << rc_.name << ": " << (converged_ ? "CONVERGED" : "NOT CONVERGED") << " ("
    << end_reason << ") ==\n";
  if (converged_) h << "converged at t = " << fmt("%.2f", converged_at_s_) << " s (simulated)\n";
  h << "agents " << final_q.size() << "/" << rc_.agents.size() << ", " << s.mode() << " mode, "
    << s.law() << " law, seed " << rc_.seed << ", " << fmt("%.2f", t_s_) << " s simulated in "
    << fmt("%.2f", wall_time_s) << " s wall\n";
  const Vec3 avg = rc_.initial_average();
  h << "initial average   (" << fmt("%.6f", avg.x()) << ", " << fmt("%.6f", avg.y()) << ", "
    << fmt("%.6f", avg.z()) << ")\n";
  h << "final mean        (" << fmt("%.6f", mean.x()) << ", " << fmt("%.6f", mean.y()) << ", "
    << fmt("%.6f", mean.z()) << ")  drift " << fmt("%.3e", s.average_drift_m()) << " m\n";
  h << "final disagreement " << fmt("%.3e", s.final_disagreement_m()) << " m, physical spread "
    << fmt("%.3e", spread) << " m, min separation " << fmt("%.3f", s.min_separation_m()) << " m\n";
  h << "lambda2 " << fmt("%.4f", s.lambda2_initial()) << " -> " << fmt("%.4f", s.lambda2_final())
    << ", edges " << s.edges_initial_size() << " -> " << s.edges_final_size() << "\n";
  h << "messages: published " << msg.published() << ", received " << msg.received() << ", dropped "
    << msg.dropped() << ", gaps " << msg.seq_gaps() << ", age p50 " << fmt("%.3f", msg.age_p50_ms())
    << " ms p99 " << fmt("%.3f", msg.age_p99_ms()) << " ms\n";
  h << "joins " << joins_ << ", departures " << departures_ << "\n";
  if (!rc_.faults.empty()) {
    const records::FaultSummary& fsum = s.faults();
    h << "faults: dropped " << fsum.dropped() << " (loss " << fsum.loss() << ", burst "
      << fsum.burst() << ", cut " << fsum.cut() << ", partition " << fsum.partition()
      << "), delayed " << fsum.delayed() << ", kills " << fsum.kills() << ", restarts "
      << fsum.restarts() << ", transport drop " << fsum.transport_drop_percent() << " %\n";
    h << "relative error of the agreed value " << fmt("%.3e", s.average_relative_error())
      << ", detect " << fmt("%.2f", s.detect_s()) << " s, reconverge "
      << fmt("%.2f", s.reconverge_s()) << " s\n";
  }
  h << "run directory: " << dir_ << "\n";
  return h.str();
}

}  // namespace qswarm
