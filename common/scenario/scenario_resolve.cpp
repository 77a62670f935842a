// resolve_scenario: a parsed scenario -> the RunConfig a run uses, every field checked and named.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <numbers>
#include <set>
#include <sstream>
#include <stdexcept>

#include "common/core/law_registry.hpp"
#include "common/scenario/scenario.hpp"
#include "common/transport/port_plan.hpp"
#include "common/transport/utf8.hpp"

namespace qswarm {

std::string quoted_number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

namespace {

[[noreturn]] void fail(const std::string& field, const std::string& expected,
                       const std::string& got) {
  throw ScenarioError("scenario field '" + field + "': expected " + expected + ", got " + got);
}

// One optional number of the scenario: where it is in the message (a dotted path), where it lands
// in RunConfig, and the range a run can honour. Its default is RunConfig's: a field the scenario
// leaves unset keeps it, and the scenario as run gets it written back. The resolver and the
// write-back both walk this table, so no default is written twice.
struct NumberField {
  const char* path;
  double& (*at)(RunConfig&);
  double lo, hi;
  bool lo_open;  // (lo, hi] instead of [lo, hi]
};

// clang-format off
const NumberField kNumberFields[] = {
  {"gain", [](RunConfig& c) -> double& { return c.agent.law.gain; }, 0.0, 1e3, true},
  {"weight.scale", [](RunConfig& c) -> double& { return c.agent.law.weight.scale; }, 0.0, 1e3, true},
  {"topology.threshold_m", [](RunConfig& c) -> double& { return c.agent.law.topology.threshold_m; }, 0.0, 1e6, true},
  {"topology.hysteresis_m", [](RunConfig& c) -> double& { return c.agent.law.topology.hysteresis_m; }, 0.0, 1e6, false},
  {"rates.physics_hz", [](RunConfig& c) -> double& { return c.agent.physics_hz; }, 0.0, 2e4, true},
  {"rates.consensus_hz", [](RunConfig& c) -> double& { return c.agent.consensus_hz; }, 1.0, 1e3, false},
  {"gains.pos_natural_freq_radps", [](RunConfig& c) -> double& { return c.agent.gains.pos_natural_freq_radps; }, 0.0, 1e3, true},
  {"gains.pos_damping", [](RunConfig& c) -> double& { return c.agent.gains.pos_damping; }, 0.0, 1e3, true},
  {"gains.att_natural_freq_radps", [](RunConfig& c) -> double& { return c.agent.gains.att_natural_freq_radps; }, 0.0, 1e4, true},
  {"gains.att_damping", [](RunConfig& c) -> double& { return c.agent.gains.att_damping; }, 0.0, 1e3, true},
  {"gains.max_tilt_rad", [](RunConfig& c) -> double& { return c.agent.gains.max_tilt_rad; }, 0.0, 1e9, true},
  {"limits.reference_speed_mps", [](RunConfig& c) -> double& { return c.agent.reference_speed_mps; }, 0.0, 1e3, true},
  {"limits.reference_accel_mps2", [](RunConfig& c) -> double& { return c.agent.reference_accel_mps2; }, 0.0, 1e3, true},
  {"limits.rotor_min_radps", [](RunConfig& c) -> double& { return c.agent.airframe.rotor_min_radps; }, 0.0, 1e4, false},
  {"limits.rotor_max_radps", [](RunConfig& c) -> double& { return c.agent.airframe.rotor_max_radps; }, 0.0, 1e4, true},
  {"avoidance.safe_distance_m", [](RunConfig& c) -> double& { return c.agent.avoidance.safe_distance_m; }, 0.0, 100.0, true},
  {"transport.neighbor_timeout_s", [](RunConfig& c) -> double& { return c.agent.neighbor_timeout_s; }, 0.0, 3600.0, true},
  {"convergence.tolerance_m", [](RunConfig& c) -> double& { return c.judge.tolerance_m; }, 0.0, 1e9, true},
  {"convergence.hold_s", [](RunConfig& c) -> double& { return c.judge.hold_s; }, 0.0, 1e6, false},
  {"duration_s", [](RunConfig& c) -> double& { return c.judge.duration_s; }, 0.0, 1e7, true},
};
// The record's rate: checked as a number, but unset it stays the plan's to choose.
const NumberField kRecordRate = {"record.rate_hz", nullptr, 0.0, 1e3, true};
// clang-format on

using google::protobuf::FieldDescriptor;
using google::protobuf::Message;

// The message that holds the last field of `path`, and that field; nullptr when a message on the
// way is unset (so is the field).
const Message* holder(const Message& root, const std::string& path, const FieldDescriptor*& fd) {
  const Message* m = &root;
  std::size_t from = 0;
  for (std::size_t dot = path.find('.'); dot != std::string::npos; dot = path.find('.', from)) {
    const FieldDescriptor* sub = m->GetDescriptor()->FindFieldByName(path.substr(from, dot - from));
    if (!m->GetReflection()->HasField(*m, sub)) return nullptr;
    m = &m->GetReflection()->GetMessage(*m, sub);
    from = dot + 1;
  }
  fd = m->GetDescriptor()->FindFieldByName(path.substr(from));
  return m;
}

void check_range(const NumberField& f, double v) {
  const bool below = f.lo_open ? v <= f.lo : v < f.lo;
  if (!std::isfinite(v) || below || v > f.hi) {
    fail(f.path,
         std::string("a finite value in ") + (f.lo_open ? "(" : "[") + quoted_number(f.lo) + ", " +
             quoted_number(f.hi) + "]",
         quoted_number(v));
  }
}

// Every number the scenario sets, checked and copied into rc; unset ones keep rc's defaults.
void resolve_numbers(const scenario::Scenario& s, RunConfig& rc) {
  for (const NumberField& f : kNumberFields) {
    const FieldDescriptor* fd = nullptr;
    const Message* m = holder(s, f.path, fd);
    if (!m || !m->GetReflection()->HasField(*m, fd)) continue;
    const double v = m->GetReflection()->GetDouble(*m, fd);
    check_range(f, v);
    f.at(rc) = v;
  }
}

void write_back_numbers(RunConfig& rc, scenario::Scenario& s) {
  for (const NumberField& f : kNumberFields) {
    Message* m = &s;
    const std::string path = f.path;
    std::size_t from = 0;
    for (std::size_t dot = path.find('.'); dot != std::string::npos; dot = path.find('.', from)) {
      m = m->GetReflection()->MutableMessage(
          m, m->GetDescriptor()->FindFieldByName(path.substr(from, dot - from)));
      from = dot + 1;
    }
    m->GetReflection()->SetDouble(m, m->GetDescriptor()->FindFieldByName(path.substr(from)),
                                  f.at(rc));
  }
}

Vec3 vec(const scenario::Vec3& v) { return Vec3(v.x(), v.y(), v.z()); }

// The law a scenario names: `law` names the three shipped laws as an enum (scenario files from
// before the law seam); any registered law goes by `law_name`.
std::string law_named(const scenario::Scenario& s) {
  if (!s.law_name().empty()) return s.law_name();
  return s.law() == scenario::LAPLACIAN ? "laplacian"
         : s.law() == scenario::W_MSR   ? "w-msr"
                                        : "edge-flow";
}

// The plant a scenario names: `mode` names the two shipped plants as an enum (scenario files from
// before the plant seam); any registered plant goes by `plant`.
std::string plant_named(const scenario::Scenario& s) {
  if (!s.plant().empty()) return s.plant();
  return s.mode() == scenario::QUADCOPTER ? "quadcopter" : "particle";
}

void resolve_plant(const scenario::Scenario& s, RunConfig& rc) {
  if (!scenario::Mode_IsValid(s.mode()))
    fail("mode", "PARTICLE or QUADCOPTER", std::to_string(static_cast<int>(s.mode())));
  if (!s.plant().empty() && s.mode() != scenario::MODE_UNSPECIFIED)
    fail("plant", "either mode or plant", "both");
  const PlantSpec* spec = nullptr;
  try {
    spec = &find_plant(plant_named(s));
  } catch (const std::invalid_argument&) {
    fail("plant", "one of " + plant_names(), "'" + s.plant() + "'");
  }
  rc.agent.plant.name = spec->name;
  try {
    rc.agent.plant.params = resolve_plant_params(
        *spec, std::map<std::string, double>(s.plant_params().begin(), s.plant_params().end()));
  } catch (const std::invalid_argument& e) {
    throw ScenarioError(std::string("scenario ") + e.what());
  }
}

void apply_overrides(scenario::Scenario& s, const ScenarioOverrides& o) {
  if (o.seed >= 0) s.set_seed(static_cast<std::uint64_t>(o.seed));
  if (o.duration_s >= 0) s.set_duration_s(o.duration_s);
  if (o.domain_id >= 0)
    s.mutable_transport()->set_domain_id(static_cast<std::uint32_t>(o.domain_id));
  if (!o.keystore.empty()) s.mutable_transport()->set_keystore(o.keystore);
  if (!o.law.empty()) {
    std::string name;
    try {
      name = find_law(o.law).name;
    } catch (const std::invalid_argument&) {
      fail("--law", "one of " + law_names(), o.law);
    }
    // Another law than the scenario's: the scenario's parameters were its law's, not this one's.
    std::string before;
    try {
      before = find_law(law_named(s)).name;
    } catch (const std::invalid_argument&) {
      // The scenario's own law is unknown: resolve_law names it.
    }
    if (name != before) {
      s.clear_wmsr_f();
      s.mutable_law_params()->clear();
    }
    s.set_law(scenario::LAW_UNSPECIFIED);
    s.set_law_name(name);
  }
  if (!o.plant.empty()) {
    std::string name;
    try {
      name = find_plant(o.plant).name;
    } catch (const std::invalid_argument&) {
      fail("--plant", "one of " + plant_names(), o.plant);
    }
    std::string before;
    try {
      before = find_plant(plant_named(s)).name;
    } catch (const std::invalid_argument&) {
      // The scenario's own plant is unknown: resolve_plant names it.
    }
    // Another plant: its parameters, and whether avoidance is on (a scenario as run says it for its
    // own plant), were that plant's.
    if (name != before) {
      s.mutable_plant_params()->clear();
      s.mutable_avoidance()->clear_enabled();
    }
    s.set_mode(scenario::MODE_UNSPECIFIED);
    s.set_plant(name);
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
    fail("random_agents.box_m", "a finite value in (0, 100000]", quoted_number(box));
  std::vector<AgentSpec> specs;
  try {
    specs = random_agent_specs(static_cast<int>(n), seed, box, min_separation_m);
  } catch (const std::runtime_error& e) {
    fail("random_agents.box_m",
         "a cube with room for " + std::to_string(n) + " agents avoidance.safe_distance_m (" +
             quoted_number(min_separation_m) + " m) apart",
         quoted_number(box) + " (" + e.what() + ")");
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
           "(" + quoted_number(p.x()) + ", " + quoted_number(p.y()) + ", " + quoted_number(p.z()) +
               ")");
    if (!std::isfinite(a.yaw_deg()) || std::abs(a.yaw_deg()) > 3600.0)
      fail(f + ".yaw_deg", "a finite angle within +-3600 deg", quoted_number(a.yaw_deg()));
    rc.agents.push_back({a.id(), p, a.yaw_deg() * std::numbers::pi / 180.0});
  }
}

// Avoidance is on by default for a plant that follows a reference and refused for one that is
// where its law puts it (the point agent); its safe distance keeps two airframes apart.
void resolve_avoidance(const scenario::Scenario& s, RunConfig& rc) {
  const scenario::Avoidance& a = s.avoidance();
  const PlantSpec& plant = rc.agent.plant_spec();
  const bool follows = plant.follows_reference;
  if (a.has_enabled() && a.enabled() && !follows) {
    fail("avoidance.enabled",
         "false or unset for plant " + plant.name +
             " (it is where its law puts it, which the filter must never change; a plant that "
             "flies, e.g. plant: \"quadcopter\", keeps the safe distance)",
         "true");
  }
  rc.agent.avoidance.enabled = a.has_enabled() ? a.enabled() : follows;
  // Quadcopters closer than two arms overlap: a smaller safe distance would let the record call a
  // collision safe.
  const double span = 2.0 * rc.agent.airframe.arm_m;
  if (plant.airframe && rc.agent.avoidance.safe_distance_m < span)
    fail("avoidance.safe_distance_m",
         "at least " + quoted_number(span) + " m for plant " + plant.name +
             " (two airframes' arms: closer, their rotors overlap)",
         quoted_number(rc.agent.avoidance.safe_distance_m));
}

// With avoidance on, listed starts must keep the safe distance: the run would begin in a violation.
void check_start_separation(const scenario::Scenario& s, const RunConfig& rc) {
  if (!rc.agent.avoidance.enabled) return;
  for (std::size_t i = 0; i < rc.agents.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      const double d = (rc.agents[i].position_W - rc.agents[j].position_W).norm();
      if (d < rc.agent.avoidance.safe_distance_m) {
        fail("agents[" + std::to_string(i) + "].position",
             "at least avoidance.safe_distance_m (" +
                 quoted_number(rc.agent.avoidance.safe_distance_m) +
                 " m) from every other start, or avoidance { enabled: false }",
             quoted_number(d) + " m from agent " + std::to_string(rc.agents[j].id) + " (of " +
                 std::to_string(s.agents_size()) + ")");
      }
    }
  }
}

// Slots: the shape's, by ascending id, overridden by an agent's own offset.
void resolve_formation(scenario::Scenario& s, RunConfig& rc) {
  const scenario::Formation& f = s.formation();
  // Not part of RunConfig (it only places the slots), so its default is here.
  const double spacing = f.has_spacing_m() ? f.spacing_m() : 3.0;
  if (!std::isfinite(spacing) || spacing <= 0.0 || spacing > 1e4)
    fail("formation.spacing_m", "a finite value in (0, 10000]", quoted_number(spacing));
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
           "(" + quoted_number(o.x()) + ", " + quoted_number(o.y()) + ", " + quoted_number(o.z()) +
               ")");
    }
    a.offset_W = o;
    any = true;
  }
  // Written back with or without a formation: the scenario as run states every default.
  s.mutable_formation()->set_spacing_m(spacing);
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
}

void resolve_law(const scenario::Scenario& s, RunConfig& rc) {
  LawConfig& law = rc.agent.law;
  if (!s.law_name().empty() && s.law() != scenario::LAW_UNSPECIFIED)
    fail("law_name", "either law or law_name", "both");
  const LawSpec* spec = nullptr;
  try {
    spec = &find_law(law_named(s));
  } catch (const std::invalid_argument&) {
    fail("law_name", "one of " + law_names(), "'" + s.law_name() + "'");
  }
  const std::string& name = spec->name;
  law.law = name;
  std::map<std::string, double> given(s.law_params().begin(), s.law_params().end());
  if (s.has_wmsr_f()) {
    if (name != "w-msr") fail("wmsr_f", "law: W_MSR (it is W-MSR's F)", "another law");
    if (given.count("f")) fail("wmsr_f", "wmsr_f or law_params[\"f\"]", "both");
    given["f"] = s.wmsr_f();
  }
  try {
    law.params = resolve_law_params(*spec, given);
  } catch (const std::invalid_argument& e) {
    throw ScenarioError(std::string("scenario ") + e.what());
  }
  switch (s.weight().policy()) {
    case scenario::UNWEIGHTED:
      law.weight.policy = WeightPolicy::kUnweighted;
      break;
    case scenario::INITIAL_DISTANCE:
      law.weight.policy = WeightPolicy::kInitialDistance;
      break;
    case scenario::INVERSE_DISTANCE:
      law.weight.policy = WeightPolicy::kInverseDistance;
      break;
    default:
      law.weight.policy = WeightPolicy::kDistance;
      break;
  }
  switch (s.topology().policy()) {
    case scenario::FIXED:
      law.topology.policy = TopologyPolicy::kFixed;
      break;
    case scenario::PROXIMITY:
      law.topology.policy = TopologyPolicy::kProximity;
      break;
    case scenario::RANGE:
      law.topology.policy = TopologyPolicy::kRange;
      break;
    default:
      law.topology.policy = TopologyPolicy::kStickyProximity;
      break;
  }
  const scenario::Topology& t = s.topology();
  for (int i = 0; i < t.edges_size(); ++i) {
    const scenario::Edge& e = t.edges(i);
    const std::string f = "topology.edges[" + std::to_string(i) + "]";
    if (!rc.spec(e.a())) fail(f + ".a", "the id of a listed agent", std::to_string(e.a()));
    if (!rc.spec(e.b())) fail(f + ".b", "the id of a listed agent", std::to_string(e.b()));
    if (e.a() == e.b())
      fail(f, "two different agents", std::to_string(e.a()) + "-" + std::to_string(e.b()));
    law.topology.edges.emplace_back(e.a(), e.b());
  }
  if (law.topology.policy == TopologyPolicy::kFixed && law.topology.edges.empty() &&
      rc.agents.size() > 1) {
    fail("topology.edges", "at least one edge for a FIXED topology", "none");
  }
}

// What holds between fields: rates a tick can keep, a controller and airframe that fly, a timeout a
// neighbour can meet.
void check_agent(RunConfig& rc) {
  AgentConfig& a = rc.agent;
  const PlantSpec& plant = a.plant_spec();
  if (a.physics_hz < plant.min_physics_hz)
    fail("rates.physics_hz",
         ">= " + quoted_number(plant.min_physics_hz) + " for plant " + plant.name,
         quoted_number(a.physics_hz));
  if (plant.max_accel_mps2) {
    const double can = plant.max_accel_mps2(a.plant.params);
    const double asked =
        std::max(a.reference_accel_mps2, a.avoidance.enabled ? a.avoidance.brake_mps2 : 0.0);
    if (can < asked)
      fail("plant_params",
           "a plant that follows its reference's " + quoted_number(asked) +
               " m/s^2 (limits.reference_accel_mps2, or avoidance's braking when on)",
           "plant " + plant.name + " accelerating at most " + quoted_number(can) + " m/s^2");
  }
  if (a.consensus_hz > a.physics_hz)
    fail("rates.consensus_hz", "at most rates.physics_hz", quoted_number(a.consensus_hz));
  // Each consensus tick runs a whole number of physics steps; a rate that does not divide the
  // physics rate would silently run at another rate than the record says.
  const double ratio = a.physics_hz / a.consensus_hz;
  if (std::abs(ratio - std::round(ratio)) > 1e-9 * ratio) {
    fail("rates.consensus_hz",
         "a divisor of rates.physics_hz (" + quoted_number(a.physics_hz) + ")",
         quoted_number(a.consensus_hz));
  }
  try {
    a.gains.validate();
  } catch (const std::invalid_argument& e) {
    throw ScenarioError(std::string("scenario field '") + e.what());
  }
  try {
    a.airframe.validate();
  } catch (const std::invalid_argument& e) {
    throw ScenarioError(std::string("scenario limits: ") + e.what());
  }
  // At least two consensus ticks: a shorter timeout makes every neighbour flap.
  if (a.neighbor_timeout_s < 2.0 / a.consensus_hz) {
    fail("transport.neighbor_timeout_s",
         "a finite value in [" + quoted_number(2.0 / a.consensus_hz) +
             ", 3600] (two consensus ticks)",
         quoted_number(a.neighbor_timeout_s));
  }
}

void resolve_transport(const scenario::Transport& t, RunConfig& rc) {
  TransportConfig& tc = rc.transport;
  if (t.has_domain_id()) tc.domain_id = t.domain_id();
  // The port plan's domains (common/transport/port_plan.hpp): each holds 545 participants.
  if (tc.domain_id > PortPlan::kMaxDomain)
    fail("transport.domain_id", "0.." + std::to_string(PortPlan::kMaxDomain),
         std::to_string(tc.domain_id));
  if (t.has_interface()) tc.interface = t.interface();
  if (tc.interface.empty())
    fail("transport.interface", "an IPv4 address such as 127.0.0.1", "\"\"");
  if (t.has_shared_memory()) tc.shared_memory = t.shared_memory();
  if (t.has_multicast()) tc.multicast = t.multicast();
  if (t.receive() != scenario::Transport::RECEIVE_UNSPECIFIED)
    tc.tick_receive = t.receive() == scenario::Transport::TICK;
  tc.run_id = t.run_id();
  if (!t.keystore().empty()) {
    std::error_code ec;
    const std::filesystem::path ks = std::filesystem::absolute(t.keystore(), ec);
    // With an error code: a symlink loop is bad input, not an exception out of the resolver.
    if (ec || !std::filesystem::is_directory(ks, ec) || ec)
      fail("transport.keystore", "a directory written by `swarm keys`", t.keystore());
    tc.keystore = ks.lexically_normal().string();
  }
  switch (t.delivery()) {
    case scenario::Transport::ALL:
      tc.delivery = Delivery::kAll;
      break;
    case scenario::Transport::REACH:
      tc.delivery = Delivery::kReach;
      break;
    case scenario::Transport::NEIGHBOURS:
      tc.delivery = Delivery::kNeighbours;
      break;
    default:
      break;  // the plan's
  }
  if (t.discovery() == scenario::Transport::SERVER) tc.discovery = Discovery::kServer;
  if (t.discovery() == scenario::Transport::SIMPLE) tc.discovery = Discovery::kSimple;
}

// Checks shared by the fault entries: agent ids, time windows, probabilities.
class FaultFields {
 public:
  explicit FaultFields(const RunConfig& rc) : rc_(rc) {}
  void agent(const std::string& field, std::uint32_t id, bool zero_ok) const {
    if ((id == 0 && !zero_ok) || (id != 0 && !rc_.spec(id))) {
      fail(field, zero_ok ? "0 (any) or the id of a listed agent" : "the id of a listed agent",
           std::to_string(id));
    }
  }
  void window(const std::string& field, double start, double end) const {
    if (!std::isfinite(start) || start < 0.0 || start > 1e7)
      fail(field + ".start_s", "a time in [0, 1e7]", quoted_number(start));
    if (!std::isfinite(end) || (end != 0.0 && (end <= start || end > 1e7))) {
      fail(field + ".end_s", "0 (never) or a time after start_s", quoted_number(end));
    }
  }
  void probability(const std::string& field, double p) const {
    if (!std::isfinite(p) || p < 0.0 || p > 1.0)
      fail(field, "a probability in [0, 1]", quoted_number(p));
  }
  void time(const std::string& field, double t) const {
    if (!std::isfinite(t) || t <= 0.0 || t > 1e7)
      fail(field, "a time in (0, 1e7]", quoted_number(t));
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
      fail(fld + ".mean_s", "a delay in [0, 60] s", quoted_number(d.mean_s()));
    }
    if (!std::isfinite(d.jitter_s()) || d.jitter_s() < 0.0 || d.jitter_s() > 60.0) {
      fail(fld + ".jitter_s", "a jitter in [0, 60] s", quoted_number(d.jitter_s()));
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
      fail(fld + ".restart_at_s", "0 (no restart) or a time after at_s",
           quoted_number(k.restart_at_s()));
    }
    for (const auto& prev : plan.kill) {
      const double prev_end = prev.restarts() ? prev.restart_at_s : 1e300;
      if (prev.agent == k.agent() && k.at_s() < prev_end && k.at_s() + 1e-9 > prev.at_s) {
        fail(fld + ".at_s", "a time after the agent's previous restart", quoted_number(k.at_s()));
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
  if (rc.faults.transport_drop_percent > 0 && rc.transport.shared_memory) {
    fail("faults.transport_drop_percent",
         "transport.shared_memory off (shared memory bypasses the test transport)",
         "shared_memory on");
  }
}

// Every default written back, so that the run directory's scenario says exactly what ran.
void write_back_defaults(RunConfig& rc, scenario::Scenario& s) {
  write_back_numbers(rc, s);
  s.set_seed(rc.seed);
  s.clear_wmsr_f();
  s.mutable_law_params()->clear();
  for (const auto& [name, value] : rc.agent.law.params) (*s.mutable_law_params())[name] = value;
  s.mutable_plant_params()->clear();
  for (const auto& [name, value] : rc.agent.plant.params) (*s.mutable_plant_params())[name] = value;
  s.mutable_transport()->set_domain_id(rc.transport.domain_id);
  s.mutable_transport()->set_interface(rc.transport.interface);
  s.mutable_transport()->set_shared_memory(rc.transport.shared_memory);
  s.mutable_transport()->set_multicast(rc.transport.multicast);
  if (rc.transport.tick_receive)
    s.mutable_transport()->set_receive(*rc.transport.tick_receive ? scenario::Transport::TICK
                                                                  : scenario::Transport::THREADS);
  if (!rc.transport.keystore.empty()) s.mutable_transport()->set_keystore(rc.transport.keystore);
  s.mutable_transport()->set_run_id(rc.transport.run_id);
  s.mutable_avoidance()->set_enabled(rc.agent.avoidance.enabled);
}

}  // namespace

RunConfig resolve_scenario(scenario::Scenario s, const ScenarioOverrides& o) {
  apply_overrides(s, o);
  RunConfig rc;
  if (s.has_seed()) rc.seed = s.seed();
  if (rc.seed > 0xFFFFFFFFull) fail("seed", "a value below 2^32", std::to_string(rc.seed));
  // Text that reaches a viewer, the record and the run directory's name: UTF-8, as a person wrote
  // it (a byte that is not ends every standard viewer's session, and cuts summary.json's name).
  for (const auto& [field, text] :
       {std::pair{"name", &s.name()}, std::pair{"description", &s.description()}})
    if (!valid_utf8(*text)) fail(field, "text in UTF-8", "bytes that are not UTF-8");
  if (!s.name().empty()) rc.name = s.name();
  resolve_plant(s, rc);
  resolve_numbers(s, rc);
  resolve_avoidance(s, rc);
  const AvoidanceConfig& av = rc.agent.avoidance;
  expand_random_agents(s, rc.seed, av.enabled ? av.safe_distance_m : 0.0);
  resolve_agents(s, rc);
  check_start_separation(s, rc);
  resolve_formation(s, rc);
  resolve_law(s, rc);
  check_agent(rc);
  if (s.record().has_rate_hz()) {
    check_range(kRecordRate, s.record().rate_hz());
    rc.judge.record_hz = s.record().rate_hz();
  }
  resolve_transport(s.transport(), rc);
  resolve_faults(s.faults(), rc);
  write_back_defaults(rc, s);
  rc.resolved = std::move(s);
  // Planned for `swarm run` on this host; the plan's decisions join the scenario as run.
  Hosts here;
  here.interface = rc.transport.interface == "any" ? "" : rc.transport.interface;
  replan(rc, here);
  return rc;
}

}  // namespace qswarm
