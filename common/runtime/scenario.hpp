#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/core/airframe.hpp"
#include "common/core/tracking_controller.hpp"
#include "common/core/update_law.hpp"
#include "common/runtime/faults.hpp"
#include "common/transport/state_message.hpp"
#include "proto/scenario.pb.h"

namespace qswarm {

// Bad scenario input: the message names the field (and line for syntax) and what was expected.
class ScenarioError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct AgentSpec {
  AgentId id = 0;
  Vec3 position_W = Vec3::Zero();
  double yaw_rad = 0.0;
};

// A scenario with every default filled in and random agents resolved: what a run actually uses.
struct RunConfig {
  std::string name;
  std::vector<AgentSpec> agents;
  AgentMode mode = AgentMode::kParticle;
  LawConfig law;
  double physics_hz = 500.0;
  double consensus_hz = 50.0;
  Airframe airframe;
  TrackingGains gains;
  double reference_speed_mps = 3.0;
  double reference_accel_mps2 = 2.0;
  double tolerance_m = 0.01;
  double hold_s = 1.0;
  double duration_s = 60.0;
  std::uint64_t seed = 1;
  std::uint32_t domain_id = 0;
  std::string interface = "127.0.0.1";
  bool shared_memory = false;
  double neighbor_timeout_s = 1.0;
  FaultPlan faults;
  scenario::Scenario resolved;  // the scenario as run (agents listed, defaults explicit)

  Vec3 initial_average() const;
  const AgentSpec* agent(AgentId id) const;
};

// Overrides from the command line, applied before validation.
struct ScenarioOverrides {
  int agents = -1;         // --agents N: replace the agent list with N seeded random agents
  std::string law;         // --law laplacian|edge-flow
  std::int64_t seed = -1;  // --seed S
  double duration_s = -1;  // --duration S
  int domain_id = -1;      // --domain D
};

scenario::Scenario parse_scenario_text(const std::string& text, const std::string& source);
scenario::Scenario read_scenario_file(const std::string& path);
RunConfig resolve_scenario(scenario::Scenario s, const ScenarioOverrides& o = {});
RunConfig load_scenario(const std::string& path, const ScenarioOverrides& o = {});
std::string to_text(const scenario::Scenario& s);

// CLI shortcuts for the common faults; each throws ScenarioError naming the flag. They add to the
// scenario's fault plan.
void add_loss_shortcut(scenario::Scenario& s, double probability);      // --loss 0.3
void add_cut_shortcut(scenario::Scenario& s, const std::string& spec);  // --cut 1-2@5:15
void add_partition_shortcut(scenario::Scenario& s,
                            const std::string& spec);                     // --partition 1,2@5:15
void add_delay_shortcut(scenario::Scenario& s, const std::string& spec);  // --delay 0.05:0.02
void add_kill_shortcut(scenario::Scenario& s, const std::string& spec);   // --kill 3@10:20
// --random-cuts N: N cuts of random links (ids 1..agents) lasting 1-5 s, starting in [2 s, 75% of
// end_s) so that the swarm has the rest of the run to agree again; seeded.
void add_random_cuts(scenario::Scenario& s, int n, int agents, double end_s, std::uint64_t seed);

// n agents uniformly in a cube of side box_m, ids 1..n, from the seed (same as the in-process
// swarm).
std::vector<AgentSpec> random_agent_specs(int n, std::uint64_t seed, double box_m);

}  // namespace qswarm
