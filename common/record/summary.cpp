#include "common/record/summary.hpp"
#include "common/core/law_registry.hpp"

#include <google/protobuf/struct.pb.h>

#include <algorithm>
#include <cstdio>
#include <sstream>

#include "common/core/graph.hpp"

#include "common/scenario/proto_util.hpp"

namespace qswarm {
namespace {

// The summary's counts are uint32 (JSON numbers, not the strings proto3 makes of uint64): a count
// past 2^32 - 1 (about 46 h of a 512-agent swarm's samples) saturates there instead of wrapping.
std::uint32_t count32(std::uint64_t n) {
  return static_cast<std::uint32_t>(std::min<std::uint64_t>(n, 4294967295ULL));
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

std::vector<AgentId> RunTally::impersonated() const {
  std::vector<AgentId> out;
  for (const auto& [key, note] : forgeries)
    if (key.second == kTwoWriters) out.push_back(key.first);
  return out;
}

records::Summary build_summary(const RunConfig& rc, const Presence& presence,
                               const ConvergenceJudge& judge, const RunTally& tally,
                               const std::optional<records::GraphSnapshot>& first,
                               const std::optional<records::GraphSnapshot>& last,
                               const RunEnd& end) {
  records::Summary s;
  s.set_scenario(rc.name);
  const bool converged = judge.converged() && tally.impersonated().empty();
  s.set_converged(converged);
  s.set_run_id(rc.transport.run_id);
  s.set_foreign_samples(tally.foreign_samples);
  s.set_implausible_samples(tally.implausible_samples);
  for (const AgentId id : judge.missing()) s.add_missing_agents(id);
  for (const AgentId id : judge.outliers()) s.add_outlier_agents(id);
  if (judge.agreed_elsewhere_m() >= 0.0) s.set_agreed_elsewhere_m(judge.agreed_elsewhere_m());
  s.set_convergence_time_s(converged ? judge.converged_at_s() : -1.0);
  for (const auto& [key, note] : tally.forgeries) {
    records::Forgery* f = s.add_forgeries();
    f->set_agent(key.first);
    f->set_kind(suspect_name(static_cast<SuspectKind>(key.second)));
    for (const AgentId by : note.noticed_by) f->add_noticed_by(by);
    f->set_first_t_s(note.first_t_s);
  }
  s.set_end_reason(end.reason);
  s.set_wall_time_s(end.wall_time_s);
  s.set_duration_s(end.t_s);
  s.set_seed(static_cast<std::uint32_t>(rc.seed));
  s.set_mode(rc.agent.plant_spec().name);
  s.set_law(rc.agent.law.law);
  s.set_secure(!rc.transport.keystore.empty());
  s.set_agents_expected(static_cast<std::uint32_t>(rc.agents.size()));
  s.set_joins(tally.joins);
  s.set_departures(tally.departures);
  s.set_min_separation_m(tally.min_separation_m < 1e299 ? tally.min_separation_m : 0.0);
  if (tally.min_separation_m < 1e299) {
    s.set_min_separation_t_s(tally.min_separation_t_s);
    s.add_min_separation_agents(tally.min_separation_a);
    s.add_min_separation_agents(tally.min_separation_b);
  }
  s.set_avoidance(rc.agent.avoidance.enabled);
  s.set_safe_distance_m(rc.agent.avoidance.safe_distance_m);
  s.set_separation_violations(tally.separation_violations);
  for (const AgentId id : tally.held) s.add_held_agents(id);
  put_vec3(s.mutable_initial_average(), rc.initial_average());

  Positions final_q, final_p;
  records::Messages& msg = *s.mutable_messages();
  double rate_sum = 0.0;
  int rate_n = 0;
  std::uint64_t published = 0, received = 0, dropped = 0, gaps = 0;
  for (const auto& [id, a] : presence.tracks()) {
    records::AgentSummary* as = s.add_agents();
    as->set_id(id);
    const AgentSpec* spec = rc.spec(id);
    put_vec3(as->mutable_initial_position(), spec ? spec->position_W : a.first.view.q0);
    if (!a.seen) continue;
    if (!a.ran) s.add_never_ran_agents(id);
    put_vec3(as->mutable_final_position(), a.last.p_W);
    put_vec3(as->mutable_final_consensus(), a.last.view.q);
    as->set_samples(count32(a.samples));
    as->set_seq_gaps(count32(a.gaps));
    as->set_dropped_by_agent(count32(a.last.dropped));
    as->set_trimmed(a.last.trimmed);
    if (const auto h = tally.hosts.find(id); h != tally.hosts.end())
      for (const std::string& host : h->second) as->add_hosts(host);
    const double span = a.last.stamp_s - a.first.stamp_s;
    if (span > 0.0) {
      as->set_rate_hz(static_cast<double>(a.samples - 1) / (span / end.time_scale));
      rate_sum += as->rate_hz();
      ++rate_n;
    }
    if (spec) {
      final_q.push_back(a.last.view.q);
      final_p.push_back(a.last.p_W);
    }
    published += a.last.seq;
    received += a.samples;
    dropped += a.last.dropped;
    gaps += a.gaps;
  }
  if (tally.resilience) {
    records::ResilienceOverTime& r = *s.mutable_resilience();
    r = *tally.resilience;
    std::uint64_t trimmed = 0;
    for (const records::AgentSummary& as : s.agents()) trimmed += as.trimmed();
    r.set_trimmed(trimmed);
  }
  msg.set_published(count32(published));
  msg.set_received(count32(received));
  msg.set_dropped(count32(dropped));
  msg.set_seq_gaps(count32(gaps));
  msg.set_age_p50_ms(percentile(tally.ages_ms, 0.50));
  msg.set_age_p99_ms(percentile(tally.ages_ms, 0.99));
  msg.set_rate_hz(rate_n ? rate_sum / rate_n : 0.0);
  msg.set_unrecorded(count32(tally.unrecorded));
  const Vec3 mean = average(final_q);
  put_vec3(s.mutable_final_consensus_mean(), mean);
  // Every agent's slot about the agreed centre, and how far from it the agent ended.
  double max_slot_error = 0.0;
  for (records::AgentSummary& as : *s.mutable_agents()) {
    const AgentSpec* spec = rc.spec(as.id());
    const Vec3 offset = spec ? spec->offset_W : Vec3::Zero();
    put_vec3(as.mutable_offset(), offset);
    if (as.final_position_size() != 3 || final_q.empty()) continue;
    const Vec3 p(as.final_position(0), as.final_position(1), as.final_position(2));
    as.set_slot_error_m((p - (mean + offset)).norm());
    max_slot_error = std::max(max_slot_error, as.slot_error_m());
  }
  s.set_max_slot_error_m(max_slot_error);
  s.set_average_drift_m(final_q.empty() ? 0.0 : (mean - rc.initial_average()).norm());
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
  if (first) {
    s.set_lambda2_initial(first->lambda2());
    edges_of(*first, s.mutable_edges_initial());
  }
  if (last) {
    s.set_lambda2_final(last->lambda2());
    edges_of(*last, s.mutable_edges_final());
  }
  records::FaultSummary& fs = *s.mutable_faults();
  FaultCounters total;
  for (const auto& [key, c] : tally.fault_counts) total += c;
  records::FaultCounts& injected = *fs.mutable_injected();
  injected.set_loss(count32(total.loss));
  injected.set_burst(count32(total.burst));
  injected.set_cut(count32(total.cut));
  injected.set_partition(count32(total.partition));
  injected.set_delayed(count32(total.delayed));
  fs.set_dropped(count32(total.dropped()));
  for (const auto& k : rc.faults.kill) {
    if (k.at_s <= end.t_s) fs.set_kills(fs.kills() + 1);
    if (k.restart_at_s > k.at_s && k.restart_at_s <= end.t_s) fs.set_restarts(fs.restarts() + 1);
  }
  for (const auto& j : rc.faults.late_join)
    if (j.at_s <= end.t_s) fs.set_late_joins(fs.late_joins() + 1);
  fs.set_transport_drop_percent(rc.faults.transport_drop_percent);
  fs.set_events(tally.fault_events);
  double detect = 0.0;
  for (double d : tally.detect_s) detect += d;
  s.set_detect_s(tally.detect_s.empty() ? -1.0
                                        : detect / static_cast<double>(tally.detect_s.size()));
  const double last_fault = rc.faults.last_fault_end_s();
  s.set_last_fault_end_s(last_fault);
  s.set_reconverge_s(
      converged && last_fault > 0.0 ? std::max(0.0, judge.converged_at_s() - last_fault) : -1.0);
  const double avg_norm = rc.initial_average().norm();
  s.set_average_relative_error(avg_norm > 0 ? s.average_drift_m() / avg_norm : s.average_drift_m());
  return s;
}

std::string summary_text(const records::Summary& s, const RunConfig& rc, const std::string& dir) {
  std::size_t final_agents = 0;
  for (const auto& a : s.agents()) final_agents += a.final_consensus_size() == 3 ? 1 : 0;
  std::ostringstream h;
  h << "\n== " << rc.name << ": " << (s.converged() ? "CONVERGED" : "NOT CONVERGED") << " ("
    << s.end_reason() << ") ==\n";
  if (s.converged())
    h << "converged at t = " << fmt("%.2f", s.convergence_time_s()) << " s (simulated)\n";
  h << "agents " << final_agents << "/" << rc.agents.size() << ", " << s.mode() << " mode, "
    << s.law() << " law, " << (s.secure() ? "DDS-Security on" : "plain DDS") << ", seed " << rc.seed
    << ", " << fmt("%.2f", s.duration_s()) << " s simulated in " << fmt("%.2f", s.wall_time_s())
    << " s wall\n";
  const Vec3 avg = rc.initial_average();
  const Vec3 mean(s.final_consensus_mean(0), s.final_consensus_mean(1), s.final_consensus_mean(2));
  const records::Messages& msg = s.messages();
  h << "initial average   (" << fmt("%.6f", avg.x()) << ", " << fmt("%.6f", avg.y()) << ", "
    << fmt("%.6f", avg.z()) << ")\n";
  h << "final mean        (" << fmt("%.6f", mean.x()) << ", " << fmt("%.6f", mean.y()) << ", "
    << fmt("%.6f", mean.z()) << ")  drift " << fmt("%.3e", s.average_drift_m()) << " m\n";
  h << "final disagreement " << fmt("%.3e", s.final_disagreement_m()) << " m, physical spread "
    << fmt("%.3e", s.max_final_spread_m()) << " m, min separation "
    << fmt("%.3f", s.min_separation_m()) << " m";
  if (s.min_separation_agents_size() == 2) {
    h << " (agents " << s.min_separation_agents(0) << " and " << s.min_separation_agents(1)
      << " at t = " << fmt("%.2f", s.min_separation_t_s()) << " s)";
  }
  h << "\n";
  if (rc.agent.plant_spec().follows_reference || s.avoidance()) {
    h << "safe distance " << fmt("%g", s.safe_distance_m()) << " m, collision avoidance "
      << (s.avoidance() ? "on" : "off") << ": " << s.separation_violations()
      << (s.separation_violations() == 1 ? " violation" : " violations") << "\n";
  }
  if (s.held_agents_size() > 0) {
    double lo = 1e300, hi = 0.0;
    for (const auto& a : s.agents()) {
      if (a.final_position_size() != 3 || std::find(s.held_agents().begin(), s.held_agents().end(),
                                                    a.id()) == s.held_agents().end())
        continue;
      lo = std::min(lo, a.slot_error_m());
      hi = std::max(hi, a.slot_error_m());
    }
    h << s.held_agents_size()
      << " agents have slots closer to another's than avoidance keeps them apart";
    if (hi >= lo) {
      h << ": they ended " << fmt("%.3f", lo) << " to " << fmt("%.3f", hi) << " m from their slots";
    }
    h << "\n";
  }
  if (rc.has_formation()) {
    h << "formation: every agent within " << fmt("%.3f", s.max_slot_error_m())
      << " m of its slot about the agreed centre\n";
  }
  h << "lambda2 " << fmt("%.4f", s.lambda2_initial()) << " -> " << fmt("%.4f", s.lambda2_final())
    << ", edges " << s.edges_initial_size() << " -> " << s.edges_final_size() << "\n";
  h << "messages: published " << msg.published() << ", received " << msg.received() << ", dropped "
    << msg.dropped() << ", gaps " << msg.seq_gaps() << ", age p50 " << fmt("%.3f", msg.age_p50_ms())
    << " ms p99 " << fmt("%.3f", msg.age_p99_ms()) << " ms\n";
  if (msg.unrecorded() > 0)
    h << "BEHIND: " << msg.unrecorded()
      << " samples arrived while the supervisor's inbox was full and were not recorded\n";
  h << "joins " << s.joins() << ", departures " << s.departures() << "\n";
  std::map<std::string, int> per_host;  // agents last seen on each host
  for (const records::AgentSummary& as : s.agents())
    if (as.hosts_size() > 0) ++per_host[as.hosts(as.hosts_size() - 1)];
  if (!per_host.empty()) {
    h << "hosts " << per_host.size() << ":";
    int shown = 0;
    for (const auto& [host, n] : per_host) {
      if (++shown > 4) {
        h << " and " << per_host.size() - 4 << " more";
        break;
      }
      h << (shown > 1 ? "," : "") << " " << host << " (" << n << (n == 1 ? " agent)" : " agents)");
    }
    h << "\n";
  }
  if (s.has_agreed_elsewhere_m() && honest_hull_f(rc.agent.law) >= 0) {
    h << "MOVED: the agents agreed " << fmt("%.3g", s.agreed_elsewhere_m())
      << " m outside their initial bounding box, which " << rc.agent.law.law
      << " keeps with at most F = " << honest_hull_f(rc.agent.law)
      << " liars on a robust graph: more liars, or too few links?\n";
  } else if (s.has_agreed_elsewhere_m()) {
    h << "MOVED: the agents agreed " << fmt("%.3g", s.agreed_elsewhere_m())
      << " m from the initial average, which " << rc.agent.law.law
      << " keeps exactly: something outside the law "
         "moved it (a participant publishing forged states or flows?)\n";
  }
  for (const records::Forgery& f : s.forgeries()) {
    h << "FORGED: agent " << f.agent() << ": " << f.kind()
      << " from t = " << fmt("%.2f", f.first_t_s()) << " s, noticed by";
    const char* sep = " ";
    for (const auto by : f.noticed_by()) {
      h << sep << (by == 0 ? std::string("the supervisor") : "agent " + std::to_string(by));
      sep = ", ";
    }
    h << "\n";
  }
  if (s.outlier_agents_size() > 0) {
    h << "OUTLIERS: the others agreed, but not agent(s)";
    for (const auto id : s.outlier_agents()) h << " " << id;
    h << " (a liar " << rc.agent.law.law
      << " ignored, or an agent cut off: the record cannot tell which)\n";
  }
  if (s.has_resilience()) {
    const records::ResilienceOverTime& r = s.resilience();
    h << rc.agent.law.law << ", F = " << r.f() << ": fewest neighbours " << r.min_degree()
      << " (needs " << 2 * r.f() + 1 << ")";
    if (r.degree_short_s() > 0.0) h << ", short for " << fmt("%.2f", r.degree_short_s()) << " s";
    if (r.has_robust_always())
      h << ", (" << r.f() + 1 << ", " << r.f() + 1 << ")-robust "
        << (r.robust_always() ? "throughout" : "NOT for " + fmt("%.2f", r.not_robust_s()) + " s");
    h << ", neighbour values trimmed " << r.trimmed() << "\n";
  }
  if (s.never_ran_agents_size() > 0) {
    h << "NEVER RAN: " << s.never_ran_agents_size()
      << " agent(s) were heard only at their start barrier:";
    constexpr int kShown = 20;
    for (int i = 0; i < std::min(kShown, s.never_ran_agents_size()); ++i)
      h << " " << s.never_ran_agents(i);
    if (s.never_ran_agents_size() > kShown) h << " ...";
    h << "\n";
  }
  if (s.missing_agents_size() > 0) {
    h << "MISSING: the others agreed without agent(s)";
    for (const auto id : s.missing_agents()) h << " " << id;
    h << "\n";
  }
  if (!rc.faults.empty()) {
    const records::FaultSummary& fsum = s.faults();
    const records::FaultCounts& inj = fsum.injected();
    h << "faults: dropped " << fsum.dropped() << " (loss " << inj.loss() << ", burst "
      << inj.burst() << ", cut " << inj.cut() << ", partition " << inj.partition() << "), delayed "
      << inj.delayed() << ", kills " << fsum.kills() << ", restarts " << fsum.restarts()
      << ", transport drop " << fsum.transport_drop_percent() << " %\n";
    h << "relative error of the agreed value " << fmt("%.3e", s.average_relative_error())
      << ", detect " << fmt("%.2f", s.detect_s()) << " s, reconverge "
      << fmt("%.2f", s.reconverge_s()) << " s\n";
  }
  h << "run directory: " << dir << "\n";
  return h.str();
}

}  // namespace qswarm
