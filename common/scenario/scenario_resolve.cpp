// resolve_scenario: a parsed scenario -> the RunConfig a run uses, every field checked and named.
#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <set>
#include <sstream>
#include <stdexcept>

#include "common/scenario/scenario.hpp"

namespace qswarm {
namespace {

[[noreturn]] void fail(const std::string& field, const std::string& expected,
                       const std::string& got) {
  throw ScenarioError("scenario field '" + field + "': expected " + expected + ", got " + got);
}

std::string num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// A finite value in [lo, hi] when present, else the default.
double ranged(const std::string& field, bool has, double value, double dflt, double lo, double hi,
              bool lo_open = false) {
  if (!has) return dflt;
  const bool below = lo_open ? value <= lo : value < lo;
  if (!std::isfinite(value) || below || value > hi) {
    fail(field,
         std::string("a finite value in ") + (lo_open ? "(" : "[") + num(lo) + ", " + num(hi) + "]",
         num(value));
  }
  return value;
}
double positive(const std::string& field, bool has, double value, double dflt, double hi = 1e9) {
  return ranged(field, has, value, dflt, 0.0, hi, true);
}

Vec3 vec(const scenario::Vec3& v) { return Vec3(v.x(), v.y(), v.z()); }

void apply_overrides(scenario::Scenario& s, const ScenarioOverrides& o) {
  if (o.seed >= 0) s.set_seed(static_cast<std::uint64_t>(o.seed));
  if (o.duration_s >= 0) s.set_duration_s(o.duration_s);
  if (o.domain_id >= 0)
    s.mutable_transport()->set_domain_id(static_cast<std::uint32_t>(o.domain_id));
  if (!o.law.empty()) {
    if (o.law == "laplacian") {
      s.set_law(scenario::LAPLACIAN);
    } else if (o.law == "edge-flow" || o.law == "edge_flow") {
      s.set_law(scenario::EDGE_FLOW);
    } else {
      fail("--law", "laplacian or edge-flow", o.law);
    }
  }
  if (o.agents >= 0) {
    s.clear_agents();
    s.mutable_random_agents()->set_count(static_cast<std::uint32_t>(o.agents));
  }
}

// Random agents become a listed swarm (the scenario as run lists them).
// With avoidance on, random starts keep the safe distance (a run must not start in a violation).
void expand_random_agents(scenario::Scenario& s, std::uint64_t seed, double min_separation_m) {
  if (s.agents_size() > 0 && s.random_agents().count() > 0) {
    fail("random_agents", "either agents or random_agents, not both", "both");
  }
  if (s.random_agents().count() == 0) return;
  const std::uint32_t n = s.random_agents().count();
  if (n > kMaxSwarmAgents)
    fail("random_agents.count", "1.." + std::to_string(kMaxSwarmAgents), std::to_string(n));
  const double box = s.random_agents().box_m() == 0.0 ? 30.0 : s.random_agents().box_m();
  if (!std::isfinite(box) || box <= 0.0 || box > 1e5)
    fail("random_agents.box_m", "a finite value in (0, 100000]", num(box));
  std::vector<AgentSpec> specs;
  try {
    specs = random_agent_specs(static_cast<int>(n), seed, box, min_separation_m);
  } catch (const std::runtime_error& e) {
    fail("random_agents.box_m",
         "a cube with room for " + std::to_string(n) + " agents avoidance.safe_distance_m (" +
             num(min_separation_m) + " m) apart",
         num(box) + " (" + e.what() + ")");
  }
  for (const AgentSpec& a : specs) {
    scenario::Agent* pa = s.add_agents();
    pa->set_id(a.id);
    pa->mutable_position()->set_x(a.position_W.x());
    pa->mutable_position()->set_y(a.position_W.y());
    pa->mutable_position()->set_z(a.position_W.z());
  }
  s.clear_random_agents();
}

void resolve_agents(const scenario::Scenario& s, RunConfig& rc) {
  if (s.agents_size() == 0)
    fail("agents", "at least one agent (or random_agents / --agents N)", "none");
  if (static_cast<std::size_t>(s.agents_size()) > kMaxSwarmAgents) {
    fail("agents", "at most " + std::to_string(kMaxSwarmAgents) + " agents",
         std::to_string(s.agents_size()));
  }
  std::map<AgentId, int> seen;
  for (int i = 0; i < s.agents_size(); ++i) {
    const scenario::Agent& a = s.agents(i);
    const std::string f = "agents[" + std::to_string(i) + "]";
    if (a.id() == 0) fail(f + ".id", "an id > 0", "0 (unset?)");
    if (seen.count(a.id())) {
      fail(f + ".id", "a unique id",
           std::to_string(a.id()) + " (also agents[" + std::to_string(seen[a.id()]) + "])");
    }
    seen[a.id()] = i;
    const Vec3 p = vec(a.position());
    if (!p.allFinite() || p.cwiseAbs().maxCoeff() > 1e5)
      fail(f + ".position", "finite coordinates within 100 km",
           "(" + num(p.x()) + ", " + num(p.y()) + ", " + num(p.z()) + ")");
    if (!std::isfinite(a.yaw_deg()) || std::abs(a.yaw_deg()) > 3600.0)
      fail(f + ".yaw_deg", "a finite angle within +-3600 deg", num(a.yaw_deg()));
    rc.agents.push_back({a.id(), p, a.yaw_deg() * std::numbers::pi / 180.0});
  }
}

void resolve_avoidance(const scenario::Scenario& s, RunConfig& rc) {
  const scenario::Avoidance& a = s.avoidance();
  const bool quad = s.mode() == scenario::QUADCOPTER;
  if (a.has_enabled() && a.enabled() && !quad) {
    fail("avoidance.enabled",
         "false or unset in PARTICLE mode (a point agent flies its consensus state, which the "
         "filter must never change; use mode: QUADCOPTER)",
         "true");
  }
  rc.avoidance.enabled = a.has_enabled() ? a.enabled() : quad;
  rc.avoidance.safe_distance_m = positive("avoidance.safe_distance_m", a.has_safe_distance_m(),
                                          a.safe_distance_m(), 1.0, 100.0);
  // Quadcopters closer than two arms overlap: a smaller safe distance would let the record call a
  // collision safe.
  const double span = 2.0 * rc.airframe.arm_m;
  if (quad && rc.avoidance.safe_distance_m < span)
    fail("avoidance.safe_distance_m",
         "at least " + num(span) +
             " m in QUADCOPTER mode (two airframes' arms: closer, their rotors overlap)",
         num(rc.avoidance.safe_distance_m));
}

// With avoidance on, listed starts must keep the safe distance: the run would begin in a violation.
void check_start_separation(const scenario::Scenario& s, const RunConfig& rc) {
  if (!rc.avoidance.enabled) return;
  for (std::size_t i = 0; i < rc.agents.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      const double d = (rc.agents[i].position_W - rc.agents[j].position_W).norm();
      if (d < rc.avoidance.safe_distance_m) {
        fail("agents[" + std::to_string(i) + "].position",
             "at least avoidance.safe_distance_m (" + num(rc.avoidance.safe_distance_m) +
                 " m) from every other start, or avoidance { enabled: false }",
             num(d) + " m from agent " + std::to_string(rc.agents[j].id) + " (of " +
                 std::to_string(s.agents_size()) + ")");
      }
    }
  }
}

// Slots: the shape's, by ascending id, overridden by an agent's own offset.
void resolve_formation(scenario::Scenario& s, RunConfig& rc) {
  const scenario::Formation& f = s.formation();
  const double spacing =
      positive("formation.spacing_m", f.has_spacing_m(), f.spacing_m(), 3.0, 1e4);
  std::vector<AgentId> ids;
  for (const AgentSpec& a : rc.agents) ids.push_back(a.id);
  std::sort(ids.begin(), ids.end());
  const std::vector<Vec3> slots =
      formation_slots(static_cast<int>(f.shape()), static_cast<int>(ids.size()), spacing);
  std::map<AgentId, Vec3> slot_of;
  for (std::size_t k = 0; k < ids.size(); ++k) slot_of[ids[k]] = slots[k];
  bool any =
      f.shape() != scenario::Formation::SHAPE_UNSPECIFIED && f.shape() != scenario::Formation::NONE;
  for (int i = 0; i < s.agents_size(); ++i) {
    AgentSpec& a = rc.agents[static_cast<std::size_t>(i)];
    a.offset_W = slot_of[a.id];
    if (!s.agents(i).has_offset()) continue;
    const Vec3 o = vec(s.agents(i).offset());
    if (!o.allFinite() || o.cwiseAbs().maxCoeff() > 1e4) {
      fail("agents[" + std::to_string(i) + "].offset", "finite coordinates within 10 km",
           "(" + num(o.x()) + ", " + num(o.y()) + ", " + num(o.z()) + ")");
    }
    a.offset_W = o;
    any = true;
  }
  if (!any) return;
  // Two agents on one slot would be flown into each other on purpose.
  for (std::size_t i = 0; i < rc.agents.size(); ++i) {
    for (std::size_t j = i + 1; j < rc.agents.size(); ++j) {
      if ((rc.agents[i].offset_W - rc.agents[j].offset_W).norm() < 1e-6) {
        fail("formation", "a different slot for every agent",
             "agents " + std::to_string(rc.agents[i].id) + " and " +
                 std::to_string(rc.agents[j].id) + " on one slot");
      }
    }
  }
  s.mutable_formation()->set_spacing_m(spacing);
}

void resolve_law(const scenario::Scenario& s, RunConfig& rc) {
  rc.law.kind = s.law() == scenario::LAPLACIAN ? LawKind::kLaplacian : LawKind::kEdgeFlow;
  rc.law.gain = positive("gain", s.has_gain(), s.gain(), 1.0, 1e3);
  switch (s.weight().policy()) {
    case scenario::UNWEIGHTED:
      rc.law.weight.policy = WeightPolicy::kUnweighted;
      break;
    case scenario::INITIAL_DISTANCE:
      rc.law.weight.policy = WeightPolicy::kInitialDistance;
      break;
    case scenario::INVERSE_DISTANCE:
      rc.law.weight.policy = WeightPolicy::kInverseDistance;
      break;
    default:
      rc.law.weight.policy = WeightPolicy::kDistance;
      break;
  }
  rc.law.weight.scale =
      positive("weight.scale", s.weight().has_scale(), s.weight().scale(), 1.0, 1e3);
  switch (s.topology().policy()) {
    case scenario::FIXED:
      rc.law.topology.policy = TopologyPolicy::kFixed;
      break;
    case scenario::PROXIMITY:
      rc.law.topology.policy = TopologyPolicy::kProximity;
      break;
    case scenario::RANGE:
      rc.law.topology.policy = TopologyPolicy::kRange;
      break;
    default:
      rc.law.topology.policy = TopologyPolicy::kStickyProximity;
      break;
  }
  const scenario::Topology& t = s.topology();
  rc.law.topology.threshold_m =
      positive("topology.threshold_m", t.has_threshold_m(), t.threshold_m(), 12.5, 1e6);
  rc.law.topology.hysteresis_m =
      ranged("topology.hysteresis_m", t.has_hysteresis_m(), t.hysteresis_m(), 0.5, 0.0, 1e6);
  for (int i = 0; i < t.edges_size(); ++i) {
    const scenario::Edge& e = t.edges(i);
    const std::string f = "topology.edges[" + std::to_string(i) + "]";
    if (!rc.agent(e.a())) fail(f + ".a", "the id of a listed agent", std::to_string(e.a()));
    if (!rc.agent(e.b())) fail(f + ".b", "the id of a listed agent", std::to_string(e.b()));
    if (e.a() == e.b())
      fail(f, "two different agents", std::to_string(e.a()) + "-" + std::to_string(e.b()));
    rc.law.topology.edges.emplace_back(e.a(), e.b());
  }
  if (rc.law.topology.policy == TopologyPolicy::kFixed && rc.law.topology.edges.empty() &&
      rc.agents.size() > 1) {
    fail("topology.edges", "at least one edge for a FIXED topology", "none");
  }
}

void resolve_rates(const scenario::Rates& r, RunConfig& rc) {
  rc.physics_hz = positive("rates.physics_hz", r.has_physics_hz(), r.physics_hz(), 500.0, 20000.0);
  rc.consensus_hz =
      ranged("rates.consensus_hz", r.has_consensus_hz(), r.consensus_hz(), 50.0, 1.0, 1000.0);
  if (rc.mode == AgentMode::kQuadcopter && rc.physics_hz < 500.0)
    fail("rates.physics_hz", ">= 500 in QUADCOPTER mode", num(rc.physics_hz));
  if (rc.consensus_hz > rc.physics_hz)
    fail("rates.consensus_hz", "at most rates.physics_hz", num(rc.consensus_hz));
  // Each consensus tick runs a whole number of physics steps; a rate that does not divide the
  // physics rate would silently run at another rate than the record says.
  const double ratio = rc.physics_hz / rc.consensus_hz;
  if (std::abs(ratio - std::round(ratio)) > 1e-9 * ratio) {
    fail("rates.consensus_hz", "a divisor of rates.physics_hz (" + num(rc.physics_hz) + ")",
         num(rc.consensus_hz));
  }
}

void resolve_gains(const scenario::Gains& g, TrackingGains& out) {
  out.pos_natural_freq_radps =
      positive("gains.pos_natural_freq_radps", g.has_pos_natural_freq_radps(),
               g.pos_natural_freq_radps(), out.pos_natural_freq_radps, 1e3);
  out.pos_damping =
      positive("gains.pos_damping", g.has_pos_damping(), g.pos_damping(), out.pos_damping, 1e3);
  out.att_natural_freq_radps =
      positive("gains.att_natural_freq_radps", g.has_att_natural_freq_radps(),
               g.att_natural_freq_radps(), out.att_natural_freq_radps, 1e4);
  out.att_damping =
      positive("gains.att_damping", g.has_att_damping(), g.att_damping(), out.att_damping, 1e3);
  out.max_tilt_rad =
      positive("gains.max_tilt_rad", g.has_max_tilt_rad(), g.max_tilt_rad(), out.max_tilt_rad);
  try {
    out.validate();
  } catch (const std::invalid_argument& e) {
    throw ScenarioError(std::string("scenario field '") + e.what());
  }
}

void resolve_limits(const scenario::Limits& l, RunConfig& rc) {
  rc.reference_speed_mps = positive("limits.reference_speed_mps", l.has_reference_speed_mps(),
                                    l.reference_speed_mps(), 3.0, 1e3);
  rc.reference_accel_mps2 = positive("limits.reference_accel_mps2", l.has_reference_accel_mps2(),
                                     l.reference_accel_mps2(), 2.0, 1e3);
  rc.airframe.rotor_min_radps = ranged("limits.rotor_min_radps", l.has_rotor_min_radps(),
                                       l.rotor_min_radps(), rc.airframe.rotor_min_radps, 0.0, 1e4);
  rc.airframe.rotor_max_radps = positive("limits.rotor_max_radps", l.has_rotor_max_radps(),
                                         l.rotor_max_radps(), rc.airframe.rotor_max_radps, 1e4);
  try {
    rc.airframe.validate();
  } catch (const std::invalid_argument& e) {
    throw ScenarioError(std::string("scenario limits: ") + e.what());
  }
}

void resolve_transport(const scenario::Transport& t, RunConfig& rc) {
  rc.domain_id = t.has_domain_id() ? t.domain_id() : 0;
  if (rc.domain_id > 232) fail("transport.domain_id", "0..232", std::to_string(rc.domain_id));
  rc.interface = t.has_interface() ? t.interface() : "127.0.0.1";
  if (rc.interface.empty())
    fail("transport.interface", "an IPv4 address such as 127.0.0.1", "\"\"");
  rc.shared_memory = t.has_shared_memory() && t.shared_memory();
  // At least two consensus ticks: a shorter timeout makes every neighbour flap.
  rc.run_id = t.run_id();
  rc.neighbor_timeout_s = ranged("transport.neighbor_timeout_s", t.has_neighbor_timeout_s(),
                                 t.neighbor_timeout_s(), 1.0, 2.0 / rc.consensus_hz, 3600.0);
}

// Checks shared by the fault entries: agent ids, time windows, probabilities.
class FaultFields {
 public:
  explicit FaultFields(const RunConfig& rc) : rc_(rc) {}
  void agent(const std::string& field, std::uint32_t id, bool zero_ok) const {
    if ((id == 0 && !zero_ok) || (id != 0 && !rc_.agent(id))) {
      fail(field, zero_ok ? "0 (any) or the id of a listed agent" : "the id of a listed agent",
           std::to_string(id));
    }
  }
  void window(const std::string& field, double start, double end) const {
    if (!std::isfinite(start) || start < 0.0 || start > 1e7)
      fail(field + ".start_s", "a time in [0, 1e7]", num(start));
    if (!std::isfinite(end) || (end != 0.0 && (end <= start || end > 1e7))) {
      fail(field + ".end_s", "0 (never) or a time after start_s", num(end));
    }
  }
  void probability(const std::string& field, double p) const {
    if (!std::isfinite(p) || p < 0.0 || p > 1.0) fail(field, "a probability in [0, 1]", num(p));
  }
  void time(const std::string& field, double t) const {
    if (!std::isfinite(t) || t <= 0.0 || t > 1e7) fail(field, "a time in (0, 1e7]", num(t));
  }

 private:
  const RunConfig& rc_;
};

std::string at(const char* kind, int i) {
  return std::string("faults.") + kind + "[" + std::to_string(i) + "]";
}

void resolve_link_faults(const scenario::Faults& f, const FaultFields& check, FaultPlan& plan) {
  for (int i = 0; i < f.loss_size(); ++i) {
    const auto& ls = f.loss(i);
    const std::string fld = at("loss", i);
    check.probability(fld + ".probability", ls.probability());
    check.agent(fld + ".from", ls.from(), true);
    check.agent(fld + ".to", ls.to(), true);
    check.window(fld, ls.start_s(), ls.end_s());
    plan.loss.push_back({ls.probability(), ls.from(), ls.to(), ls.start_s(), ls.end_s()});
  }
  for (int i = 0; i < f.burst_size(); ++i) {
    const auto& b = f.burst(i);
    const std::string fld = at("burst", i);
    check.probability(fld + ".p_good_to_bad", b.p_good_to_bad());
    check.probability(fld + ".p_bad_to_good", b.p_bad_to_good());
    check.probability(fld + ".loss_good", b.loss_good());
    check.probability(fld + ".loss_bad", b.loss_bad());
    check.agent(fld + ".from", b.from(), true);
    check.agent(fld + ".to", b.to(), true);
    const double loss_bad = (b.loss_bad() == 0.0 && b.loss_good() == 0.0) ? 1.0 : b.loss_bad();
    plan.burst.push_back(
        {b.p_good_to_bad(), b.p_bad_to_good(), b.loss_good(), loss_bad, b.from(), b.to()});
  }
  for (int i = 0; i < f.cut_size(); ++i) {
    const auto& c = f.cut(i);
    const std::string fld = at("cut", i);
    check.agent(fld + ".a", c.a(), false);
    check.agent(fld + ".b", c.b(), false);
    if (c.a() == c.b()) fail(fld, "two different agents", std::to_string(c.a()));
    check.window(fld, c.start_s(), c.end_s());
    plan.cut.push_back({c.a(), c.b(), c.start_s(), c.end_s(), c.directed()});
  }
  for (int i = 0; i < f.partition_size(); ++i) {
    const auto& p = f.partition(i);
    const std::string fld = at("partition", i);
    if (p.group_size() == 0) fail(fld + ".group", "at least one agent id", "none");
    for (int k = 0; k < p.group_size(); ++k) {
      check.agent(fld + ".group[" + std::to_string(k) + "]", p.group(k), false);
    }
    check.window(fld, p.start_s(), p.end_s());
    plan.partition.push_back({{p.group().begin(), p.group().end()}, p.start_s(), p.end_s()});
  }
  for (int i = 0; i < f.delay_size(); ++i) {
    const auto& d = f.delay(i);
    const std::string fld = at("delay", i);
    if (!std::isfinite(d.mean_s()) || d.mean_s() < 0.0 || d.mean_s() > 60.0) {
      fail(fld + ".mean_s", "a delay in [0, 60] s", num(d.mean_s()));
    }
    if (!std::isfinite(d.jitter_s()) || d.jitter_s() < 0.0 || d.jitter_s() > 60.0) {
      fail(fld + ".jitter_s", "a jitter in [0, 60] s", num(d.jitter_s()));
    }
    check.agent(fld + ".from", d.from(), true);
    check.agent(fld + ".to", d.to(), true);
    plan.delay.push_back({d.mean_s(), d.jitter_s(), d.from(), d.to()});
  }
}

void resolve_process_faults(const scenario::Faults& f, const FaultFields& check, FaultPlan& plan) {
  for (int i = 0; i < f.kill_size(); ++i) {
    const auto& k = f.kill(i);
    const std::string fld = at("kill", i);
    check.agent(fld + ".agent", k.agent(), false);
    check.time(fld + ".at_s", k.at_s());
    if (!std::isfinite(k.restart_at_s()) ||
        (k.restart_at_s() != 0.0 && (k.restart_at_s() <= k.at_s() || k.restart_at_s() > 1e7))) {
      fail(fld + ".restart_at_s", "0 (no restart) or a time after at_s", num(k.restart_at_s()));
    }
    for (const auto& prev : plan.kill) {
      const double prev_end = prev.restarts() ? prev.restart_at_s : 1e300;
      if (prev.agent == k.agent() && k.at_s() < prev_end && k.at_s() + 1e-9 > prev.at_s) {
        fail(fld + ".at_s", "a time after the agent's previous restart", num(k.at_s()));
      }
    }
    plan.kill.push_back({k.agent(), k.at_s(), k.restart_at_s()});
  }
  for (int i = 0; i < f.late_join_size(); ++i) {
    const auto& j = f.late_join(i);
    const std::string fld = at("late_join", i);
    check.agent(fld + ".agent", j.agent(), false);
    check.time(fld + ".at_s", j.at_s());
    if (plan.late_join_at(j.agent()))
      fail(fld + ".agent", "an agent that joins late once", std::to_string(j.agent()));
    plan.late_join.push_back({j.agent(), j.at_s()});
  }
}

void resolve_faults(const scenario::Faults& f, RunConfig& rc) {
  const FaultFields check(rc);
  resolve_link_faults(f, check, rc.faults);
  resolve_process_faults(f, check, rc.faults);
  if (f.transport_drop_percent() > 100) {
    fail("faults.transport_drop_percent", "0..100", std::to_string(f.transport_drop_percent()));
  }
  rc.faults.transport_drop_percent = f.transport_drop_percent();
  if (rc.faults.transport_drop_percent > 0 && rc.shared_memory) {
    fail("faults.transport_drop_percent",
         "transport.shared_memory off (shared memory bypasses the test transport)",
         "shared_memory on");
  }
}

// Every default written back, so that the run directory's scenario says exactly what ran.
void write_back_defaults(scenario::Scenario& s, const RunConfig& rc) {
  s.set_gain(rc.law.gain);
  s.set_duration_s(rc.duration_s);
  s.mutable_transport()->set_domain_id(rc.domain_id);
  s.mutable_transport()->set_interface(rc.interface);
  s.mutable_transport()->set_shared_memory(rc.shared_memory);
  s.mutable_transport()->set_neighbor_timeout_s(rc.neighbor_timeout_s);
  s.mutable_transport()->set_run_id(rc.run_id);
  s.mutable_rates()->set_physics_hz(rc.physics_hz);
  s.mutable_rates()->set_consensus_hz(rc.consensus_hz);
  s.mutable_convergence()->set_tolerance_m(rc.tolerance_m);
  s.mutable_convergence()->set_hold_s(rc.hold_s);
  s.mutable_topology()->set_threshold_m(rc.law.topology.threshold_m);
  s.mutable_topology()->set_hysteresis_m(rc.law.topology.hysteresis_m);
  s.mutable_weight()->set_scale(rc.law.weight.scale);
  s.mutable_avoidance()->set_enabled(rc.avoidance.enabled);
  s.mutable_avoidance()->set_safe_distance_m(rc.avoidance.safe_distance_m);
}

}  // namespace

RunConfig resolve_scenario(scenario::Scenario s, const ScenarioOverrides& o) {
  apply_overrides(s, o);
  RunConfig rc;
  rc.seed = s.has_seed() ? s.seed() : 1;
  if (rc.seed > 0xFFFFFFFFull) fail("seed", "a value below 2^32", std::to_string(rc.seed));
  s.set_seed(rc.seed);
  rc.name = s.name().empty() ? "unnamed" : s.name();
  resolve_avoidance(s, rc);
  expand_random_agents(s, rc.seed, rc.avoidance.enabled ? rc.avoidance.safe_distance_m : 0.0);
  resolve_agents(s, rc);
  check_start_separation(s, rc);
  resolve_formation(s, rc);
  rc.mode = s.mode() == scenario::QUADCOPTER ? AgentMode::kQuadcopter : AgentMode::kParticle;
  resolve_law(s, rc);
  resolve_rates(s.rates(), rc);
  resolve_gains(s.gains(), rc.gains);
  resolve_limits(s.limits(), rc);
  const scenario::Convergence& c = s.convergence();
  rc.tolerance_m = positive("convergence.tolerance_m", c.has_tolerance_m(), c.tolerance_m(), 0.01);
  rc.hold_s = ranged("convergence.hold_s", c.has_hold_s(), c.hold_s(), 1.0, 0.0, 1e6);
  rc.duration_s = positive("duration_s", s.has_duration_s(), s.duration_s(), 60.0, 1e7);
  resolve_transport(s.transport(), rc);
  resolve_faults(s.faults(), rc);
  write_back_defaults(s, rc);
  rc.resolved = s;
  return rc;
}

}  // namespace qswarm
