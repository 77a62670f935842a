#include "common/runtime/process_setup.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>

namespace qswarm {

void add_process_options(CLI::App& app, ProcessOptions& o) {
  app.add_option("--scenario", o.scenario, "scenario file (Protobuf text format)")->required();
  app.add_option("--time-scale", o.time_scale, "simulated seconds per wall second")
      ->check(CLI::PositiveNumber);
  app.add_option("--domain", o.domain, "DDS domain id (overrides the scenario)")
      ->check(CLI::Range(0, 232));
  app.add_option("--interface", o.interface,
                 "IPv4 address DDS binds to (overrides the scenario; e.g. a test host's address)");
  app.add_option("--seed", o.seed, "run seed (overrides the scenario)");
}

std::optional<RunConfig> load_for_process(const char* prog, const ProcessOptions& opts) {
  try {
    ScenarioOverrides o;
    o.domain_id = opts.domain;
    o.seed = opts.seed;
    return load_scenario(opts.scenario, o);
  } catch (const ScenarioError& e) {
    std::fprintf(stderr, "%s: %s\n", prog, e.what());
    return std::nullopt;
  }
}

DdsOptions dds_options(const RunConfig& rc, const std::string& participant_name,
                       const std::string& interface_override) {
  DdsOptions d;
  d.domain_id = rc.domain_id;
  d.participant_name = participant_name;
  d.interface = interface_override.empty() ? rc.interface : interface_override;
  d.shared_memory = rc.shared_memory;
  d.max_agents = static_cast<int>(std::max<std::size_t>(rc.agents.size(), 16));
  d.test_drop_data_percent = static_cast<std::uint8_t>(rc.faults.transport_drop_percent);
  return d;
}

AgentParams make_agent_params(const RunConfig& rc, const AgentSpec& spec) {
  AgentParams p;
  p.id = spec.id;
  p.p0_W = spec.position_W;
  p.yaw0_rad = spec.yaw_rad;
  p.mode = rc.mode;
  p.law = rc.law;
  p.physics_hz = rc.physics_hz;
  p.consensus_hz = rc.consensus_hz;
  p.airframe = rc.airframe;
  p.gains = rc.gains;
  p.reference_speed_mps = rc.reference_speed_mps;
  p.reference_accel_mps2 = rc.reference_accel_mps2;
  p.neighbor_timeout_s = rc.neighbor_timeout_s;
  p.incarnation = wall_now_ns();
  // On a FIXED graph only its listed neighbours count.
  p.expected_peers = rc.law.topology.policy == TopologyPolicy::kFixed
                         ? listed_peers(rc.law.topology, spec.id).size()
                         : rc.agents.size() - 1;
  return p;
}

}  // namespace qswarm
