#include "common/runtime/scenario.hpp"

#include <google/protobuf/io/tokenizer.h>
#include <google/protobuf/text_format.h>

#include <cmath>
#include <fstream>
#include <map>
#include <numbers>
#include <random>
#include <sstream>

namespace qswarm {
namespace {

class Collector : public google::protobuf::io::ErrorCollector {
 public:
  explicit Collector(std::string source) : source_(std::move(source)) {}
  void AddError(int line, google::protobuf::io::ColumnNumber col, const std::string& msg) override {
    if (first_.empty()) {
      first_ =
          source_ + ":" + std::to_string(line + 1) + ":" + std::to_string(col + 1) + ": " + msg;
    }
  }
  void AddWarning(int, google::protobuf::io::ColumnNumber, const std::string&) override {}
  const std::string& first() const { return first_; }

 private:
  std::string source_;
  std::string first_;
};

[[noreturn]] void fail(const std::string& field, const std::string& expected,
                       const std::string& got) {
  throw ScenarioError("scenario field '" + field + "': expected " + expected + ", got " + got);
}

std::string num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

double positive(const std::string& field, bool has, double value, double dflt) {
  if (!has) return dflt;
  if (!std::isfinite(value) || value <= 0.0) fail(field, "a finite value > 0", num(value));
  return value;
}

double non_negative(const std::string& field, bool has, double value, double dflt) {
  if (!has) return dflt;
  if (!std::isfinite(value) || value < 0.0) fail(field, "a finite value >= 0", num(value));
  return value;
}

Vec3 vec(const scenario::Vec3& v) { return Vec3(v.x(), v.y(), v.z()); }

}  // namespace

Vec3 RunConfig::initial_average() const {
  Vec3 sum = Vec3::Zero();
  for (const AgentSpec& a : agents) sum += a.position_W;
  return agents.empty() ? sum : Vec3(sum / static_cast<double>(agents.size()));
}

const AgentSpec* RunConfig::agent(AgentId id) const {
  for (const AgentSpec& a : agents)
    if (a.id == id) return &a;
  return nullptr;
}

std::vector<AgentSpec> random_agent_specs(int n, std::uint64_t seed, double box_m) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, box_m);
  std::vector<AgentSpec> out;
  for (int i = 0; i < n; ++i) {
    const double x = u(rng), y = u(rng), z = u(rng);
    out.push_back({static_cast<AgentId>(i + 1), Vec3(x, y, z), 0.0});
  }
  return out;
}

scenario::Scenario parse_scenario_text(const std::string& text, const std::string& source) {
  scenario::Scenario s;
  google::protobuf::TextFormat::Parser parser;
  Collector errors(source);
  parser.RecordErrorsTo(&errors);
  if (!parser.ParseFromString(text, &s)) {
    throw ScenarioError(errors.first().empty() ? source + ": not a valid scenario"
                                               : errors.first());
  }
  return s;
}

scenario::Scenario read_scenario_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ScenarioError(path + ": cannot open scenario file");
  std::stringstream buf;
  buf << in.rdbuf();
  return parse_scenario_text(buf.str(), path);
}

std::string to_text(const scenario::Scenario& s) {
  std::string out;
  google::protobuf::TextFormat::Printer printer;
  printer.PrintToString(s, &out);
  return out;
}

RunConfig resolve_scenario(scenario::Scenario s, const ScenarioOverrides& o) {
  RunConfig rc;
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
  rc.seed = s.has_seed() ? s.seed() : 1;
  if (rc.seed > 0xFFFFFFFFull) fail("seed", "a value below 2^32", std::to_string(rc.seed));
  s.set_seed(rc.seed);
  rc.name = s.name().empty() ? "unnamed" : s.name();

  // Agents: listed, or random from the seed (then written back as a list: the scenario as run).
  if (s.agents_size() > 0 && s.random_agents().count() > 0) {
    fail("random_agents", "either agents or random_agents, not both", "both");
  }
  if (s.random_agents().count() > 0) {
    const std::uint32_t n = s.random_agents().count();
    if (n > 512) fail("random_agents.count", "1..512", std::to_string(n));
    const double box = s.random_agents().box_m() == 0.0 ? 30.0 : s.random_agents().box_m();
    if (!std::isfinite(box) || box <= 0.0)
      fail("random_agents.box_m", "a finite value > 0", num(box));
    for (const AgentSpec& a : random_agent_specs(static_cast<int>(n), rc.seed, box)) {
      scenario::Agent* pa = s.add_agents();
      pa->set_id(a.id);
      pa->mutable_position()->set_x(a.position_W.x());
      pa->mutable_position()->set_y(a.position_W.y());
      pa->mutable_position()->set_z(a.position_W.z());
    }
    s.clear_random_agents();
  }
  if (s.agents_size() == 0)
    fail("agents", "at least one agent (or random_agents / --agents N)", "none");
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
    if (!std::isfinite(a.yaw_deg())) fail(f + ".yaw_deg", "a finite angle", num(a.yaw_deg()));
    rc.agents.push_back({a.id(), p, a.yaw_deg() * std::numbers::pi / 180.0});
  }

  rc.mode = s.mode() == scenario::QUADCOPTER ? AgentMode::kQuadcopter : AgentMode::kParticle;
  rc.law.kind = s.law() == scenario::LAPLACIAN ? LawKind::kLaplacian : LawKind::kEdgeFlow;
  rc.law.gain = positive("gain", s.has_gain(), s.gain(), 1.0);
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
  rc.law.weight.scale = positive("weight.scale", s.weight().has_scale(), s.weight().scale(), 1.0);
  switch (s.topology().policy()) {
    case scenario::FIXED:
      rc.law.topology.policy = TopologyPolicy::kFixed;
      break;
    case scenario::PROXIMITY:
      rc.law.topology.policy = TopologyPolicy::kProximity;
      break;
    default:
      rc.law.topology.policy = TopologyPolicy::kStickyProximity;
      break;
  }
  rc.law.topology.threshold_m = positive("topology.threshold_m", s.topology().has_threshold_m(),
                                         s.topology().threshold_m(), 12.5);
  rc.law.topology.hysteresis_m = non_negative(
      "topology.hysteresis_m", s.topology().has_hysteresis_m(), s.topology().hysteresis_m(), 0.5);
  for (int i = 0; i < s.topology().edges_size(); ++i) {
    const scenario::Edge& e = s.topology().edges(i);
    const std::string f = "topology.edges[" + std::to_string(i) + "]";
    if (!seen.count(e.a())) fail(f + ".a", "the id of a listed agent", std::to_string(e.a()));
    if (!seen.count(e.b())) fail(f + ".b", "the id of a listed agent", std::to_string(e.b()));
    if (e.a() == e.b())
      fail(f, "two different agents", std::to_string(e.a()) + "-" + std::to_string(e.b()));
    rc.law.topology.edges.emplace_back(e.a(), e.b());
  }
  if (rc.law.topology.policy == TopologyPolicy::kFixed && rc.law.topology.edges.empty() &&
      rc.agents.size() > 1) {
    fail("topology.edges", "at least one edge for a FIXED topology", "none");
  }

  rc.physics_hz =
      positive("rates.physics_hz", s.rates().has_physics_hz(), s.rates().physics_hz(), 500.0);
  rc.consensus_hz =
      positive("rates.consensus_hz", s.rates().has_consensus_hz(), s.rates().consensus_hz(), 50.0);
  if (rc.physics_hz > 20000.0) fail("rates.physics_hz", "at most 20000", num(rc.physics_hz));
  if (rc.mode == AgentMode::kQuadcopter && rc.physics_hz < 500.0)
    fail("rates.physics_hz", ">= 500 in QUADCOPTER mode", num(rc.physics_hz));
  if (rc.consensus_hz > rc.physics_hz)
    fail("rates.consensus_hz", "at most rates.physics_hz", num(rc.consensus_hz));

  const scenario::Gains& g = s.gains();
  rc.gains.pos_natural_freq_radps =
      positive("gains.pos_natural_freq_radps", g.has_pos_natural_freq_radps(),
               g.pos_natural_freq_radps(), rc.gains.pos_natural_freq_radps);
  rc.gains.pos_damping =
      positive("gains.pos_damping", g.has_pos_damping(), g.pos_damping(), rc.gains.pos_damping);
  rc.gains.att_natural_freq_radps =
      positive("gains.att_natural_freq_radps", g.has_att_natural_freq_radps(),
               g.att_natural_freq_radps(), rc.gains.att_natural_freq_radps);
  rc.gains.att_damping =
      positive("gains.att_damping", g.has_att_damping(), g.att_damping(), rc.gains.att_damping);
  rc.gains.max_tilt_rad =
      positive("gains.max_tilt_rad", g.has_max_tilt_rad(), g.max_tilt_rad(), rc.gains.max_tilt_rad);
  try {
    rc.gains.validate();
  } catch (const std::invalid_argument& e) {
    throw ScenarioError(std::string("scenario field '") + e.what());
  }

  const scenario::Limits& l = s.limits();
  rc.reference_speed_mps = positive("limits.reference_speed_mps", l.has_reference_speed_mps(),
                                    l.reference_speed_mps(), 3.0);
  rc.reference_accel_mps2 = positive("limits.reference_accel_mps2", l.has_reference_accel_mps2(),
                                     l.reference_accel_mps2(), 2.0);
  rc.airframe.rotor_min_radps = non_negative("limits.rotor_min_radps", l.has_rotor_min_radps(),
                                             l.rotor_min_radps(), rc.airframe.rotor_min_radps);
  rc.airframe.rotor_max_radps = positive("limits.rotor_max_radps", l.has_rotor_max_radps(),
                                         l.rotor_max_radps(), rc.airframe.rotor_max_radps);
  try {
    rc.airframe.validate();
  } catch (const std::invalid_argument& e) {
    throw ScenarioError(std::string("scenario limits: ") + e.what());
  }

  rc.tolerance_m = positive("convergence.tolerance_m", s.convergence().has_tolerance_m(),
                            s.convergence().tolerance_m(), 0.01);
  rc.hold_s = non_negative("convergence.hold_s", s.convergence().has_hold_s(),
                           s.convergence().hold_s(), 1.0);
  rc.duration_s = positive("duration_s", s.has_duration_s(), s.duration_s(), 60.0);
  const scenario::Transport& t = s.transport();
  rc.domain_id = t.has_domain_id() ? t.domain_id() : 0;
  if (rc.domain_id > 232) fail("transport.domain_id", "0..232", std::to_string(rc.domain_id));
  rc.interface = t.has_interface() ? t.interface() : "127.0.0.1";
  if (rc.interface.empty())
    fail("transport.interface", "an IPv4 address such as 127.0.0.1", "\"\"");
  rc.shared_memory = t.has_shared_memory() && t.shared_memory();
  rc.neighbor_timeout_s = positive("transport.neighbor_timeout_s", t.has_neighbor_timeout_s(),
                                   t.neighbor_timeout_s(), 1.0);

  // Faults.
  const scenario::Faults& f = s.faults();
  const auto agent_ok = [&](const std::string& field, std::uint32_t aid, bool zero_ok) {
    if ((aid == 0 && !zero_ok) || (aid != 0 && !seen.count(aid))) {
      fail(field, zero_ok ? "0 (any) or the id of a listed agent" : "the id of a listed agent",
           std::to_string(aid));
    }
  };
  const auto window = [&](const std::string& field, double start, double end) {
    if (!std::isfinite(start) || start < 0.0) fail(field + ".start_s", "a time >= 0", num(start));
    if (!std::isfinite(end) || (end != 0.0 && end <= start)) {
      fail(field + ".end_s", "0 (never) or a time after start_s", num(end));
    }
  };
  const auto prob = [&](const std::string& field, double p) {
    if (!std::isfinite(p) || p < 0.0 || p > 1.0) fail(field, "a probability in [0, 1]", num(p));
  };
  for (int i = 0; i < f.loss_size(); ++i) {
    const auto& ls = f.loss(i);
    const std::string fld = "faults.loss[" + std::to_string(i) + "]";
    prob(fld + ".probability", ls.probability());
    agent_ok(fld + ".from", ls.from(), true);
    agent_ok(fld + ".to", ls.to(), true);
    window(fld, ls.start_s(), ls.end_s());
    rc.faults.loss.push_back({ls.probability(), ls.from(), ls.to(), ls.start_s(), ls.end_s()});
  }
  for (int i = 0; i < f.burst_size(); ++i) {
    const auto& b = f.burst(i);
    const std::string fld = "faults.burst[" + std::to_string(i) + "]";
    prob(fld + ".p_good_to_bad", b.p_good_to_bad());
    prob(fld + ".p_bad_to_good", b.p_bad_to_good());
    prob(fld + ".loss_good", b.loss_good());
    prob(fld + ".loss_bad", b.loss_bad());
    agent_ok(fld + ".from", b.from(), true);
    agent_ok(fld + ".to", b.to(), true);
    const double loss_bad = (b.loss_bad() == 0.0 && b.loss_good() == 0.0) ? 1.0 : b.loss_bad();
    rc.faults.burst.push_back(
        {b.p_good_to_bad(), b.p_bad_to_good(), b.loss_good(), loss_bad, b.from(), b.to()});
  }
  for (int i = 0; i < f.cut_size(); ++i) {
    const auto& c = f.cut(i);
    const std::string fld = "faults.cut[" + std::to_string(i) + "]";
    agent_ok(fld + ".a", c.a(), false);
    agent_ok(fld + ".b", c.b(), false);
    if (c.a() == c.b()) fail(fld, "two different agents", std::to_string(c.a()));
    window(fld, c.start_s(), c.end_s());
    rc.faults.cut.push_back({c.a(), c.b(), c.start_s(), c.end_s(), c.directed()});
  }
  for (int i = 0; i < f.partition_size(); ++i) {
    const auto& p = f.partition(i);
    const std::string fld = "faults.partition[" + std::to_string(i) + "]";
    if (p.group_size() == 0) fail(fld + ".group", "at least one agent id", "none");
    for (int k = 0; k < p.group_size(); ++k) {
      agent_ok(fld + ".group[" + std::to_string(k) + "]", p.group(k), false);
    }
    window(fld, p.start_s(), p.end_s());
    rc.faults.partition.push_back({{p.group().begin(), p.group().end()}, p.start_s(), p.end_s()});
  }
  for (int i = 0; i < f.delay_size(); ++i) {
    const auto& d = f.delay(i);
    const std::string fld = "faults.delay[" + std::to_string(i) + "]";
    if (!std::isfinite(d.mean_s()) || d.mean_s() < 0.0 || d.mean_s() > 60.0) {
      fail(fld + ".mean_s", "a delay in [0, 60] s", num(d.mean_s()));
    }
    if (!std::isfinite(d.jitter_s()) || d.jitter_s() < 0.0 || d.jitter_s() > 60.0) {
      fail(fld + ".jitter_s", "a jitter in [0, 60] s", num(d.jitter_s()));
    }
    agent_ok(fld + ".from", d.from(), true);
    agent_ok(fld + ".to", d.to(), true);
    rc.faults.delay.push_back({d.mean_s(), d.jitter_s(), d.from(), d.to()});
  }
  for (int i = 0; i < f.kill_size(); ++i) {
    const auto& k = f.kill(i);
    const std::string fld = "faults.kill[" + std::to_string(i) + "]";
    agent_ok(fld + ".agent", k.agent(), false);
    if (!std::isfinite(k.at_s()) || k.at_s() <= 0.0)
      fail(fld + ".at_s", "a time > 0", num(k.at_s()));
    if (!std::isfinite(k.restart_at_s()) ||
        (k.restart_at_s() != 0.0 && k.restart_at_s() <= k.at_s())) {
      fail(fld + ".restart_at_s", "0 (no restart) or a time after at_s", num(k.restart_at_s()));
    }
    for (const auto& prev : rc.faults.kill) {
      const double prev_end = prev.restart_at_s > 0 ? prev.restart_at_s : 1e300;
      if (prev.agent == k.agent() && k.at_s() < prev_end && k.at_s() + 1e-9 > prev.at_s) {
        fail(fld + ".at_s", "a time after the agent's previous restart", num(k.at_s()));
      }
    }
    rc.faults.kill.push_back({k.agent(), k.at_s(), k.restart_at_s()});
  }
  for (int i = 0; i < f.late_join_size(); ++i) {
    const auto& j = f.late_join(i);
    const std::string fld = "faults.late_join[" + std::to_string(i) + "]";
    agent_ok(fld + ".agent", j.agent(), false);
    if (!std::isfinite(j.at_s()) || j.at_s() <= 0.0)
      fail(fld + ".at_s", "a time > 0", num(j.at_s()));
    rc.faults.late_join.push_back({j.agent(), j.at_s()});
  }
  if (f.transport_drop_percent() > 100) {
    fail("faults.transport_drop_percent", "0..100", std::to_string(f.transport_drop_percent()));
  }
  rc.faults.transport_drop_percent = f.transport_drop_percent();
  if (rc.faults.transport_drop_percent > 0 && rc.shared_memory) {
    fail("faults.transport_drop_percent",
         "transport.shared_memory off (shared memory bypasses the test transport)",
         "shared_memory on");
  }

  // Write every default back so the run directory's scenario says exactly what ran.
  s.set_gain(rc.law.gain);
  s.set_duration_s(rc.duration_s);
  s.mutable_transport()->set_domain_id(rc.domain_id);
  s.mutable_transport()->set_interface(rc.interface);
  s.mutable_transport()->set_shared_memory(rc.shared_memory);
  s.mutable_transport()->set_neighbor_timeout_s(rc.neighbor_timeout_s);
  s.mutable_rates()->set_physics_hz(rc.physics_hz);
  s.mutable_rates()->set_consensus_hz(rc.consensus_hz);
  s.mutable_convergence()->set_tolerance_m(rc.tolerance_m);
  s.mutable_convergence()->set_hold_s(rc.hold_s);
  s.mutable_topology()->set_threshold_m(rc.law.topology.threshold_m);
  s.mutable_topology()->set_hysteresis_m(rc.law.topology.hysteresis_m);
  s.mutable_weight()->set_scale(rc.law.weight.scale);
  rc.resolved = s;
  return rc;
}

namespace {

double parse_number(const std::string& flag, const std::string& text) {
  try {
    size_t used = 0;
    const double v = std::stod(text, &used);
    if (used != text.size() || !std::isfinite(v)) throw std::invalid_argument(text);
    return v;
  } catch (const std::exception&) {
    throw ScenarioError(flag + " '" + text + "': expected a number");
  }
}

// "T0:T1", or "T0" (until the end).
std::pair<double, double> parse_window(const std::string& flag, const std::string& text) {
  const auto colon = text.find(':');
  if (colon == std::string::npos) return {parse_number(flag, text), 0.0};
  return {parse_number(flag, text.substr(0, colon)), parse_number(flag, text.substr(colon + 1))};
}

std::pair<std::string, std::string> split_at(const std::string& flag, const std::string& spec,
                                             const char* expected) {
  const auto at = spec.find('@');
  if (at == std::string::npos) throw ScenarioError(flag + " '" + spec + "': expected " + expected);
  return {spec.substr(0, at), spec.substr(at + 1)};
}

std::uint32_t parse_id(const std::string& flag, const std::string& text) {
  const double v = parse_number(flag, text);
  if (v < 1 || v != std::floor(v) || v > 4e9) {
    throw ScenarioError(flag + " '" + text + "': expected an agent id");
  }
  return static_cast<std::uint32_t>(v);
}

}  // namespace

void add_loss_shortcut(scenario::Scenario& s, double p) {
  if (!std::isfinite(p) || p < 0.0 || p > 1.0) {
    throw ScenarioError("--loss " + num(p) + ": expected a probability in [0, 1]");
  }
  if (p > 0.0) s.mutable_faults()->add_loss()->set_probability(p);
}

void add_cut_shortcut(scenario::Scenario& s, const std::string& spec) {
  const auto [link, win] = split_at("--cut", spec, "A-B@START:END, e.g. 1-2@5:15");
  const auto dash = link.find('-');
  if (dash == std::string::npos) {
    throw ScenarioError("--cut '" + spec + "': expected A-B@START:END, e.g. 1-2@5:15");
  }
  auto* c = s.mutable_faults()->add_cut();
  c->set_a(parse_id("--cut", link.substr(0, dash)));
  c->set_b(parse_id("--cut", link.substr(dash + 1)));
  const auto [t0, t1] = parse_window("--cut", win);
  c->set_start_s(t0);
  c->set_end_s(t1);
}

void add_partition_shortcut(scenario::Scenario& s, const std::string& spec) {
  const auto [ids, win] = split_at("--partition", spec, "ID,ID,...@START:END, e.g. 1,2@5:15");
  auto* p = s.mutable_faults()->add_partition();
  std::stringstream in(ids);
  std::string one;
  while (std::getline(in, one, ',')) p->add_group(parse_id("--partition", one));
  const auto [t0, t1] = parse_window("--partition", win);
  p->set_start_s(t0);
  p->set_end_s(t1);
}

void add_delay_shortcut(scenario::Scenario& s, const std::string& spec) {
  const auto [mean, jitter] = parse_window("--delay", spec);
  auto* d = s.mutable_faults()->add_delay();
  d->set_mean_s(mean);
  d->set_jitter_s(jitter);
}

void add_kill_shortcut(scenario::Scenario& s, const std::string& spec) {
  const auto [who, win] = split_at("--kill", spec, "ID@AT[:RESTART], e.g. 3@10:20");
  auto* k = s.mutable_faults()->add_kill();
  k->set_agent(parse_id("--kill", who));
  const auto [t0, t1] = parse_window("--kill", win);
  k->set_at_s(t0);
  k->set_restart_at_s(t1);
}

void add_random_cuts(scenario::Scenario& s, int n, int agents, double end_s, std::uint64_t seed) {
  std::mt19937_64 rng(link_seed(seed, 0xC0, 0xC7));
  std::uniform_int_distribution<int> pick(1, std::max(2, agents));
  std::uniform_real_distribution<double> start(2.0, std::max(3.0, 0.75 * end_s - 5.0)),
      len(1.0, 5.0);
  for (int i = 0; i < n; ++i) {
    const int a = pick(rng);
    int b = pick(rng);
    while (b == a) b = pick(rng);
    auto* c = s.mutable_faults()->add_cut();
    c->set_a(static_cast<std::uint32_t>(a));
    c->set_b(static_cast<std::uint32_t>(b));
    const double t0 = start(rng);
    c->set_start_s(t0);
    c->set_end_s(t0 + len(rng));
  }
}

RunConfig load_scenario(const std::string& path, const ScenarioOverrides& o) {
  return resolve_scenario(read_scenario_file(path), o);
}

}  // namespace qswarm
