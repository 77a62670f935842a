#include "common/sim/law_kit.hpp"

#include <cstdio>
#include <functional>
#include <sstream>

#include "common/core/graph.hpp"
#include "common/record/separation.hpp"
#include "common/scenario/scenario.hpp"
#include "common/sim/in_process_swarm.hpp"

namespace qswarm {
namespace {

// How far a law may leave the initial average and still keep it "exactly": round-off over a
// run's ticks, far below anything a broken exchange leaves (a lost Laplacian step moves it by
// centimetres to metres).
constexpr double kExactM = 1e-6;
// How far outside the honest agents' initial box counts as inside (round-off).
constexpr double kInsideM = 1e-9;

std::string fmt(const char* f, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, x);
  return buf;
}

// The scenario file `name` flown by the kit's law, with `faults` (text of a Faults message) added.
RunConfig flight(const LawSpec& spec, const KitOptions& o, const std::string& name,
                 const std::string& faults = "", bool avoidance = false) {
  scenario::Scenario s = read_scenario_file((o.scenarios / name).string());
  s.set_law(scenario::LAW_UNSPECIFIED);
  s.clear_wmsr_f();
  s.set_law_name(spec.name);
  s.mutable_law_params()->clear();
  for (const auto& [k, v] : o.params) (*s.mutable_law_params())[k] = v;
  if (avoidance) s.mutable_avoidance()->set_enabled(true);
  if (!faults.empty())
    s.mutable_faults()->MergeFrom(parse_scenario_text("faults { " + faults + " }", name).faults());
  return resolve_scenario(s);
}

// Steps until every agent runs and they agree within the scenario's tolerance after `settled_s`
// (the last fault), or the scenario's duration passes.
bool fly_until_agreed(InProcessSwarm& swarm, double settled_s, const std::vector<AgentId>& skip) {
  const RunConfig& rc = swarm.config();
  const std::size_t n = rc.agents.size();
  const auto states = [&] {
    Positions q;
    for (const AgentSpec& a : rc.agents) {
      const AgentLoop* l = swarm.agent(a.id);
      bool liar = false;
      for (const AgentId s : skip) liar = liar || s == a.id;
      if (!liar && l != nullptr) q.push_back(l->runtime().consensus());
    }
    return q;
  };
  return swarm.run_until(
      [&] {
        const Positions q = states();
        return swarm.wall_s() > settled_s && swarm.running_states().size() == n &&
               q.size() == n - skip.size() && disagreement(q) < rc.judge.tolerance_m;
      },
      rc.judge.duration_s);
}

KitRow agreement(const LawSpec& spec, const KitOptions& o, const std::string& file,
                 const std::string& label) {
  InProcessSwarm swarm(flight(spec, o, file));
  KitRow r{"agreement", label, spec.claims.agreement, false, ""};
  r.kept = fly_until_agreed(swarm, 0.0, {});
  r.measured = r.kept ? "agreed in " + fmt("%.2f", swarm.wall_s()) + " s"
                      : "disagreement " + fmt("%.3g", swarm.disagreement_running()) + " m after " +
                            fmt("%.0f", swarm.wall_s()) + " s";
  return r;
}

KitRow exact_average(const LawSpec& spec, const KitOptions& o, const std::string& label,
                     const std::string& faults, double settled_s) {
  InProcessSwarm swarm(flight(spec, o, "faults_six.txtpb", faults));
  KitRow r{"exact average", label, spec.claims.exact_average, false, ""};
  const bool agreed = fly_until_agreed(swarm, settled_s, {});
  const Positions q = swarm.running_states();
  Vec3 mean = Vec3::Zero();
  for (const Vec3& x : q) mean += x;
  if (!q.empty()) mean /= static_cast<double>(q.size());
  const double off = (mean - swarm.config().initial_average()).norm();
  r.kept = agreed && off <= kExactM;
  r.measured = (agreed ? "agreed " : "did not agree; mean ") + fmt("%.2e", off) +
               " m from the initial average";
  return r;
}

KitRow honest_hull(const LawSpec& spec, const KitOptions& o, const Liar& liar) {
  InProcessSwarm swarm(flight(spec, o, "insider_seven.txtpb"));
  swarm.add_liar(liar);
  KitRow r{"honest hull", "one liar, " + to_string(liar.kind), spec.claims.honest_hull, false, ""};
  const bool agreed = fly_until_agreed(swarm, 0.0, {liar.id});
  Positions q, q0;
  for (const AgentSpec& a : swarm.config().agents) {
    if (a.id == liar.id || swarm.agent(a.id) == nullptr) continue;
    q.push_back(swarm.agent(a.id)->runtime().consensus());
    q0.push_back(a.q0());
  }
  const double out = outside_box_m(q, q0);
  r.kept = agreed && out <= kInsideM;
  r.measured = std::string(agreed ? "honest agents agreed, " : "honest agents did not agree, ") +
               fmt("%.3g", out) + " m outside their initial box";
  return r;
}

KitRow separation(const LawSpec& spec, const KitOptions& o) {
  InProcessSwarm swarm(flight(spec, o, "paper/unweighted_quadcopter.txtpb",
                              /*faults=*/"", /*avoidance=*/true));
  const RunConfig& rc = swarm.config();
  SeparationMonitor monitor(rc.agent.avoidance.safe_distance_m);
  // The record's own monitor, fed every round for the scenario's whole duration: the closest
  // approach comes as they gather, after they agree.
  swarm.run_until(
      [&] {
        for (const AgentSpec& a : rc.agents)
          if (const AgentLoop* l = swarm.agent(a.id)) {
            const QuadState& q = l->runtime().quad();
            monitor.on_sample(a.id, q.p_W, q.velocity_W(), swarm.wall_s());
          }
        return false;
      },
      rc.judge.duration_s);
  KitRow r{"separation", "paper, unweighted, quadcopters with avoidance", spec.claims.separation,
           false, ""};
  r.kept = monitor.measured() && monitor.violations() == 0;
  r.measured = "closest " + fmt("%.2f", monitor.min_m()) + " m, safe distance " +
               fmt("%.2f", rc.agent.avoidance.safe_distance_m) + " m, " +
               std::to_string(monitor.violations()) + " violations";
  return r;
}

}  // namespace

bool KitReport::passed() const {
  for (const KitRow& r : rows)
    if (r.claimed && !r.kept) return false;
  return true;
}

std::string KitReport::table() const {
  std::ostringstream o;
  o << "| law | promise | flight | claimed | kept | measured |\n| --- | --- | --- | --- | --- | "
       "--- |\n";
  for (const KitRow& r : rows) {
    o << "| " << law << " | " << r.promise << " | " << r.flight << " | "
      << (r.claimed ? "yes" : "no") << " | " << (r.kept ? "yes" : (r.claimed ? "**BROKEN**" : "no"))
      << " | " << r.measured << " |\n";
  }
  return o.str();
}

KitReport check_law(const LawSpec& spec, const KitOptions& o) {
  KitReport rep;
  rep.law = spec.name;
  rep.rows.push_back(agreement(spec, o, "paper/unweighted.txtpb", "paper, unweighted"));
  rep.rows.push_back(agreement(spec, o, "paper/weighted.txtpb", "paper, weighted"));
  rep.rows.push_back(agreement(spec, o, "paper/time_varying.txtpb", "paper, time-varying"));
  rep.rows.push_back(exact_average(spec, o, "loss 30 %", "loss { probability: 0.3 }", 0.0));
  rep.rows.push_back(
      exact_average(spec, o, "delay 50 +- 40 ms", "delay { mean_s: 0.05 jitter_s: 0.04 }", 0.0));
  rep.rows.push_back(exact_average(spec, o, "cut 1-2, 0.5 to 2.5 s",
                                   "cut { a: 1 b: 2 start_s: 0.5 end_s: 2.5 }", 2.5));
  rep.rows.push_back(exact_average(spec, o, "kill 3 at 1 s, restart at 2 s",
                                   "kill { agent: 3 at_s: 1 restart_at_s: 2 }", 2.0));
  for (const Liar& liar :
       {Liar{7, Liar::Kind::kConstant, kDefaultLie}, Liar{7, Liar::Kind::kDrift, kDefaultDrift_mps},
        Liar{7, Liar::Kind::kSplit, kDefaultLie}})
    rep.rows.push_back(honest_hull(spec, o, liar));
  rep.rows.push_back(separation(spec, o));
  return rep;
}

}  // namespace qswarm
