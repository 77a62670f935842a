#include "common/sim/law_kit.hpp"

#include <algorithm>
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
// run's ticks (edge-flow: 1e-15 to 4e-10 m here), far below anything a broken exchange leaves (a
// lost Laplacian step moves it by centimetres to metres).
constexpr double kExactM = 1e-8;
// How far outside the honest agents' initial box counts as inside (round-off).
constexpr double kInsideM = 1e-9;

std::string fmt(const char* f, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, x);
  return buf;
}

// The scenario file `name` flown by the kit's law, with `faults` (text of a Faults message) added.
RunConfig flight(const LawSpec& spec, const KitOptions& o, const std::string& name,
                 const std::string& faults = "") {
  scenario::Scenario s = read_scenario_file((o.scenarios / name).string());
  s.set_law(scenario::LAW_UNSPECIFIED);
  s.clear_wmsr_f();
  s.set_law_name(spec.name);
  s.mutable_law_params()->clear();
  for (const auto& [k, v] : o.params) (*s.mutable_law_params())[k] = v;
  if (!faults.empty())
    s.mutable_faults()->MergeFrom(parse_scenario_text("faults { " + faults + " }", name).faults());
  return resolve_scenario(s);
}

// The consensus states of the agents alive, but those in `skip`.
Positions states_of(const InProcessSwarm& swarm, const std::vector<AgentId>& skip) {
  Positions q;
  for (const AgentSpec& a : swarm.config().agents) {
    const AgentLoop* l = swarm.agent(a.id);
    if (l != nullptr && std::find(skip.begin(), skip.end(), a.id) == skip.end())
      q.push_back(l->runtime().consensus());
  }
  return q;
}

// Steps until every agent runs and those not in `skip` have stayed within the scenario's tolerance
// of their mean for its hold_s, after `settled_s` (the last fault), or the scenario's duration
// passes. `each_round` sees every round.
bool fly_until_agreed(InProcessSwarm& swarm, double settled_s, const std::vector<AgentId>& skip,
                      const std::function<void()>& each_round = {}) {
  const RunConfig& rc = swarm.config();
  const std::size_t n = rc.agents.size();
  double agreed_since = -1.0;
  return swarm.run_until(
      [&] {
        if (each_round) each_round();
        const Positions q = states_of(swarm, skip);
        const bool agreed = swarm.wall_s() > settled_s && swarm.running_states().size() == n &&
                            q.size() == n - skip.size() && disagreement(q) < rc.judge.tolerance_m;
        if (!agreed) agreed_since = -1.0;
        if (agreed && agreed_since < 0.0) agreed_since = swarm.wall_s();
        return agreed && swarm.wall_s() - agreed_since >= rc.judge.hold_s;
      },
      rc.judge.duration_s);
}

// Flies `body`; a law that throws breaks the flight (its row says what it threw).
void fly(KitRow& r, const std::function<void()>& body) {
  try {
    body();
  } catch (const std::exception& e) {
    r.kept = false;
    r.measured = std::string("the law threw: ") + e.what();
  }
}

KitRow agreement(const LawSpec& spec, const KitOptions& o, const std::string& file,
                 const std::string& label) {
  const RunConfig rc = flight(spec, o, file);
  KitRow r{"agreement", label, spec.claims.agreement, false, ""};
  fly(r, [&] {
    InProcessSwarm swarm(rc);
    r.kept = fly_until_agreed(swarm, 0.0, {});
    r.measured = r.kept ? "agreed in " + fmt("%.2f", swarm.wall_s() - rc.judge.hold_s) + " s"
                        : "disagreement " + fmt("%.3g", swarm.disagreement_running()) +
                              " m after " + fmt("%.0f", swarm.wall_s()) + " s";
  });
  return r;
}

KitRow exact_average(const LawSpec& spec, const KitOptions& o, const std::string& label,
                     const std::string& faults, double settled_s) {
  const RunConfig rc = flight(spec, o, "faults_six.txtpb", faults);
  KitRow r{"exact average", label, spec.claims.exact_average, false, ""};
  fly(r, [&] {
    InProcessSwarm swarm(rc);
    const bool agreed = fly_until_agreed(swarm, settled_s, {});
    const Positions q = swarm.running_states();
    Vec3 mean = Vec3::Zero();
    for (const Vec3& x : q) mean += x;
    if (!q.empty()) mean /= static_cast<double>(q.size());
    const double off = (mean - rc.initial_average()).norm();
    r.kept = agreed && off <= kExactM;
    r.measured = (agreed ? "agreed " : "did not agree; mean ") + fmt("%.2e", off) +
                 " m from the initial average";
  });
  return r;
}

// insider_seven: seven agents on the complete graph; the law's F liars (at least one) lie from
// the start, agents 7, 6, ... The claim holds for F >= 1 on an (F+1, F+1)-robust graph.
KitRow honest_hull(const LawSpec& spec, const KitOptions& o, Liar::Kind kind, const Vec3& value) {
  const RunConfig rc = flight(spec, o, "insider_seven.txtpb");
  const auto f_param = rc.agent.law.params.find("f");
  const int f = f_param != rc.agent.law.params.end() ? static_cast<int>(f_param->second) : 1;
  const int n = static_cast<int>(rc.agents.size());
  const int liars = std::clamp(f, 1, n - 1);
  std::vector<Edge> complete;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) complete.push_back({i, j, 1.0});
  const bool robust = f >= 1 && check_resilience(n, complete, f).ok();
  KitRow r{"honest hull",
           std::to_string(liars) + (liars == 1 ? " liar, " : " liars, ") + to_string(kind),
           spec.claims.honest_hull && robust, false, ""};
  fly(r, [&] {
    InProcessSwarm swarm(rc);
    std::vector<AgentId> skip;
    for (int k = 0; k < liars; ++k) {
      const AgentId id = rc.agents[n - 1 - k].id;
      swarm.add_liar({id, kind, value});
      skip.push_back(id);
    }
    Positions q0;
    for (const AgentSpec& a : rc.agents)
      if (std::find(skip.begin(), skip.end(), a.id) == skip.end()) q0.push_back(a.q0());
    double worst = 0.0;  // the promise is to stay inside, not to end inside
    const bool agreed = fly_until_agreed(swarm, 0.0, skip, [&] {
      worst = std::max(worst, outside_box_m(states_of(swarm, skip), q0));
    });
    r.kept = agreed && worst <= kInsideM;
    r.measured = std::string(agreed ? "honest agents agreed, " : "honest agents did not agree, ") +
                 "at most " + fmt("%.3g", worst) + " m outside their initial box";
  });
  if (spec.claims.honest_hull && !robust)
    r.measured += f < 1 ? " (F = 0: nothing claimed against a liar)"
                        : " (F = " + std::to_string(f) + ": the graph is not robust enough)";
  return r;
}

KitRow separation(const LawSpec& spec, const KitOptions& o) {
  RunConfig rc = flight(spec, o, "paper/unweighted_quadcopter.txtpb");
  rc.agent.avoidance.enabled = o.avoidance;
  KitRow r{"separation",
           std::string("paper, unweighted, quadcopters, avoidance ") + (o.avoidance ? "on" : "off"),
           spec.claims.separation && o.avoidance, false, ""};
  fly(r, [&] {
    InProcessSwarm swarm(rc);
    SeparationMonitor monitor(rc.agent.avoidance.safe_distance_m);
    // The record's own monitor, fed every round for the scenario's whole duration: the closest
    // approach comes as they gather, after they agree.
    swarm.run_until(
        [&] {
          for (const AgentSpec& a : rc.agents)
            if (const AgentLoop* l = swarm.agent(a.id)) {
              monitor.on_sample(a.id, l->runtime().position(), l->runtime().velocity(),
                                swarm.wall_s());
            }
          return false;
        },
        rc.judge.duration_s);
    r.kept = monitor.measured() && monitor.violations() == 0;
    r.measured = "closest " + fmt("%.2f", monitor.min_m()) + " m, safe distance " +
                 fmt("%.2f", rc.agent.avoidance.safe_distance_m) + " m, " +
                 std::to_string(monitor.violations()) + " violations";
  });
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
       "--- "
       "|\n";
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
  rep.rows.push_back(honest_hull(spec, o, Liar::Kind::kConstant, kDefaultLie));
  rep.rows.push_back(honest_hull(spec, o, Liar::Kind::kDrift, kDefaultDrift_mps));
  rep.rows.push_back(honest_hull(spec, o, Liar::Kind::kSplit, kDefaultLie));
  rep.rows.push_back(separation(spec, o));
  return rep;
}

}  // namespace qswarm
