#include "launcher/inspect.hpp"

#include <google/protobuf/struct.pb.h>

#include <cstdio>
#include <iostream>
#include <set>
#include <sstream>

#include "common/core/graph.hpp"
#include "common/core/law_registry.hpp"
#include "common/runtime/run_load.hpp"
#include "common/scenario/scenario.hpp"
#include "proto/records.pb.h"

#include "common/scenario/proto_util.hpp"

namespace qswarm {
namespace {

void put_row(google::protobuf::ListValue* l, std::initializer_list<double> values) {
  for (const double v : values) l->add_values()->set_number_value(v);
}

std::string as_json(const RunConfig& rc, const InitialGraph& g, double tau) {
  records::Inspection ins;
  ins.set_scenario(rc.name);
  const int n = static_cast<int>(rc.agents.size());
  for (const AgentSpec& a : rc.agents) {
    records::InspectAgent* ia = ins.add_agents();
    ia->set_id(a.id);
    for (int k = 0; k < 3; ++k) ia->add_position(a.position_W[k]);
    const Vec3 slot = rc.initial_average() + a.offset_W;
    for (int k = 0; k < 3; ++k) ia->add_offset(a.offset_W[k]);
    for (int k = 0; k < 3; ++k) ia->add_slot(slot[k]);
  }
  for (const Edge& e : g.edges)
    put_row(ins.add_edges(), {static_cast<double>(rc.agents[e.i].id),
                              static_cast<double>(rc.agents[e.j].id), e.weight});
  for (int i = 0; i < n; ++i) {
    google::protobuf::ListValue* row = ins.add_laplacian();
    for (int j = 0; j < n; ++j) row->add_values()->set_number_value(g.L(i, j));
  }
  for (int i = 0; i < n; ++i) ins.add_eigenvalues(g.spectrum.eigenvalues[i]);
  ins.set_lambda2(g.spectrum.lambda2);
  ins.set_components(static_cast<std::uint32_t>(g.spectrum.components));
  ins.set_connected(g.spectrum.components == 1);
  const Vec3 avg = rc.initial_average();
  for (int k = 0; k < 3; ++k) ins.add_agreement_point(avg[k]);
  ins.set_time_constant_s(tau);
  ins.set_avoidance(rc.agent.avoidance.enabled);
  ins.set_safe_distance_m(rc.agent.avoidance.safe_distance_m);
  for (const AgentId id : rc.held_agents()) ins.add_held_agents(id);
  *ins.mutable_resolved() = rc.resolved;
  *ins.mutable_plan() = to_proto(rc.plan);
  *ins.mutable_load() = predict_load_here(rc, rc.plan.hosts.time_scale);
  if (honest_hull_f(rc.agent.law) >= 0) {
    const ResilienceCheck c = resilience_of(rc, g);
    records::Resilience* r = ins.mutable_resilience();
    r->set_f(static_cast<std::uint32_t>(c.f));
    r->set_min_degree(static_cast<std::uint32_t>(c.min_degree));
    r->set_degree_ok(c.degree_ok);
    if (c.robust) r->set_robust(*c.robust);
    r->set_ok(c.ok());
  }
  return to_json(ins);
}

std::string as_text(const RunConfig& rc, const InitialGraph& g, double tau) {
  const Vec3 avg = rc.initial_average();
  const int n = static_cast<int>(rc.agents.size());
  std::ostringstream o;
  o.precision(6);
  o << "scenario " << rc.name << ": " << n << " agents, " << to_string(rc.agent.law.weight.policy)
    << " weights, " << to_string(rc.agent.law.topology.policy) << " topology, " << rc.agent.law.law
    << " law";
  for (const auto& [name, value] : rc.agent.law.params) o << ", " << name << " " << value;
  o << ", gain " << rc.agent.law.gain << "\n";
  o << "plant " << rc.agent.plant_spec().name;
  for (const auto& [name, value] : rc.agent.plant.params) o << ", " << name << " " << value;
  o << ": " << rc.agent.plant_spec().summary << "\n";
  o << "initial edges (" << g.edges.size() << "):";
  for (const Edge& e : g.edges)
    o << " " << rc.agents[e.i].id << "-" << rc.agents[e.j].id << " (w=" << e.weight << ")";
  o << "\nweighted Laplacian:\n";
  for (int i = 0; i < n && n <= 16; ++i) {
    for (int j = 0; j < n; ++j) {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%10.4f", g.L(i, j));
      o << buf;
    }
    o << "\n";
  }
  if (n > 16) o << "  (" << n << " x " << n << ", not printed)\n";
  o << "eigenvalues:";
  for (int i = 0; i < std::min(n, 16); ++i) o << " " << g.spectrum.eigenvalues[i];
  o << "\nlambda2 " << g.spectrum.lambda2 << ", components " << g.spectrum.components
    << (g.spectrum.components == 1 ? " (connected)"
                                   : " (NOT connected: proximity may join them later)")
    << "\npredicted agreement point (the initial average"
    << (rc.has_formation() ? " of the agents' estimates of the centre" : "") << "): (" << avg.x()
    << ", " << avg.y() << ", " << avg.z() << ")\n";
  if (tau > 0) o << "time constant 1/(k lambda2) = " << tau << " s (exact for fixed weights)\n";
  if (honest_hull_f(rc.agent.law) >= 0) o << describe(resilience_of(rc, g), rc);
  if (rc.agent.avoidance.enabled) {
    o << "collision avoidance on: every quadcopter keeps " << rc.agent.avoidance.safe_distance_m
      << " m from every agent it hears (the filter aims for "
      << rc.agent.avoidance.filter_distance_m() << " m)\n";
    const std::set<AgentId> held = rc.held_agents();
    if (!held.empty()) {
      o << "  " << held.size() << " of " << n
        << " agents have slots closer than that to another's: they end in a cluster about "
           "their slots, not on them\n";
    }
  } else if (rc.agent.plant_spec().follows_reference) {
    o << "collision avoidance off: nothing keeps the agents (plant " << rc.agent.plant_spec().name
      << ") apart (the record counts approaches closer than " << rc.agent.avoidance.safe_distance_m
      << " m)\n";
  }
  o << describe_plan(rc.plan) << describe_load(predict_load_here(rc, rc.plan.hosts.time_scale));
  if (rc.has_formation()) {
    o << "formation: the agents agree on the centre above and fly to centre + slot\n";
    o << "  agent        slot about the centre         where it ends\n";
    int shown = 0;
    for (const AgentSpec& a : rc.agents) {
      if (++shown > 32) {
        o << "  (" << n - 32 << " more not printed; --json lists every slot)\n";
        break;
      }
      const Vec3 end = avg + a.offset_W;
      char buf[160];
      std::snprintf(buf, sizeof buf, "  %5u  (%8.3f, %8.3f, %8.3f)  (%8.3f, %8.3f, %8.3f)\n", a.id,
                    a.offset_W.x(), a.offset_W.y(), a.offset_W.z(), end.x(), end.y(), end.z());
      o << buf;
    }
  }
  return o.str();
}

}  // namespace

std::string describe_plan(const RunPlan& p) {
  std::ostringstream o;
  o.precision(4);
  o << "run plan (swarm run on this host, docs/run-plan.md):\n"
    << "  who hears whom: " << to_string(p.delivery) << ", routed as " << to_string(p.routing)
    << (p.multicast_group.empty() ? ", unicast" : ", multicast group " + p.multicast_group)
    << "; agents receive " << (p.tick_receive ? "at the tick" : "on Fast DDS's threads") << "\n"
    << "  discovery: " << to_string(p.discovery)
    << (p.own_server ? " (the run's own " + std::to_string(p.own_servers) + " Discovery Servers)"
                     : std::string())
    << ", " << p.participants << " participants, announced every "
    << p.participant_announce_period_s << " s\n"
    << "  ticks: " << p.tick_phases << " phase" << (p.tick_phases > 1 ? "s" : "")
    << "; record: " << p.record_hz << " Hz (every " << p.record_every << " ticks"
    << (p.spread_records ? ", spread over them by id" : "") << "), present for "
    << p.presence_timeout_s << " s unheard\n"
    << "  start: barrier beacon " << p.barrier_waiting_period_s << " s, ready "
    << p.barrier_announce_period_s << " s, timeout " << p.start_timeout_s << " s (join "
    << p.join_timeout_s << " s); wall limits: agent " << p.agent_wall_limit_s << " s, swarm run "
    << p.launcher_wall_limit_s << " s\n";
  return o.str();
}

ResilienceCheck resilience_of(const RunConfig& rc, const InitialGraph& g) {
  return check_resilience(static_cast<int>(rc.agents.size()), g.edges,
                          std::max(0, honest_hull_f(rc.agent.law)));
}

std::string describe(const ResilienceCheck& c, const RunConfig& rc) {
  std::ostringstream o;
  const int f = c.f;
  o << rc.agent.law.law << " tolerates " << f << " lying neighbour(s) if every agent has at least "
    << 2 * f + 1 << " neighbours and the graph is (" << f + 1 << ", " << f + 1
    << ")-robust:\n  degree " << c.min_degree << (c.degree_ok ? " (enough)" : " (TOO FEW)")
    << ", robustness ";
  if (!c.robust) {
    o << "not decided (more than " << kMaxExactRobustness << " agents)";
  } else {
    o << (*c.robust ? "holds" : "FAILS");
  }
  o << "\n";
  if (!c.ok()) {
    o << (rc.agent.law.topology.policy == TopologyPolicy::kFixed
              ? "  the FIXED graph never changes: swarm run refuses this scenario\n"
              : "  the initial graph does not hold it: a liar can drag or split the honest agents "
                "until proximity adds links\n");
  }
  return o.str();
}

InitialGraph initial_graph(const RunConfig& rc) {
  InitialGraph g;
  const int n = static_cast<int>(rc.agents.size());
  for (int i = 0; i < n; ++i) {
    LinkTracker tracker(rc.agents[i].id, rc.agent.law.topology);
    for (int j = i + 1; j < n; ++j) {
      // The law's initial states: the agents' estimates of the centre (position - slot). Under
      // RANGE, links follow the physical distance; weights always follow the states.
      const double d = (rc.agents[i].q0() - rc.agents[j].q0()).norm();
      const double link_d = rc.agent.law.topology.policy == TopologyPolicy::kRange
                                ? (rc.agents[i].position_W - rc.agents[j].position_W).norm()
                                : d;
      if (tracker.update(rc.agents[j].id, link_d)) {
        g.edges.push_back({i, j, weight_for_distance(rc.agent.law.weight, d)});
      }
    }
  }
  g.L = laplacian(n, g.edges);
  g.spectrum = analyze(g.L);
  return g;
}

int inspect_scenario(const std::string& path, bool json) {
  RunConfig rc;
  try {
    rc = load_scenario(path);
  } catch (const ScenarioError& e) {
    std::cerr << "swarm inspect: " << e.what() << "\n";
    return 2;
  }
  const InitialGraph g = initial_graph(rc);
  const double tau = g.spectrum.lambda2 > 0 ? 1.0 / (rc.agent.law.gain * g.spectrum.lambda2) : -1.0;
  std::cout << (json ? as_json(rc, g, tau) : as_text(rc, g, tau));
  return 0;
}

}  // namespace qswarm
