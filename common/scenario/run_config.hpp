#pragma once

#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "common/core/agent.hpp"
#include "common/core/airframe.hpp"
#include "common/core/avoidance.hpp"
#include "common/core/plant.hpp"
#include "common/core/tracking_controller.hpp"
#include "common/core/update_law.hpp"
#include "common/scenario/fault_plan.hpp"
#include "common/scenario/run_plan.hpp"
#include "proto/scenario.pb.h"

namespace qswarm {

struct AgentSpec {
  AgentId id = 0;
  Vec3 position_W = Vec3::Zero();
  double yaw_rad = 0.0;
  Vec3 offset_W = Vec3::Zero();  // its slot relative to the swarm's centre (formation)
  // Its initial consensus state: its estimate of the centre.
  Vec3 q0() const { return position_W - offset_W; }
};

// What every agent of a run flies with: its dynamics, its law, its rates, its controller. Each
// field's default is written here once; the resolver keeps it when the scenario leaves the field
// unset and writes it back into the scenario as run.
struct AgentConfig {
  PlantConfig plant;  // the vehicle (common/plants/): the paper's point agent by default
  LawConfig law;
  double physics_hz = 500.0;
  double consensus_hz = 50.0;
  Airframe airframe;
  TrackingGains gains;
  double reference_speed_mps = 3.0;   // how fast the tracked reference may move
  double reference_accel_mps2 = 2.0;  // and accelerate
  // Collision avoidance (enabled: a plant that follows a reference has it filtered) and the safe
  // distance the record judges separation by, for every plant.
  AvoidanceConfig avoidance;
  double neighbor_timeout_s = 1.0;  // a neighbour silent this long (simulated) leaves the graph
  // Physics steps per consensus tick (the resolver refuses rates that do not divide).
  int steps_per_tick() const;
  // The plant's registered spec (find_plant).
  const PlantSpec& plant_spec() const { return find_plant(plant.name); }
};

// How the record judges the run.
struct JudgeConfig {
  double tolerance_m = 0.01;  // agreed: every state within this of the mean
  double hold_s = 1.0;        // for this long
  double duration_s = 60.0;   // simulated seconds before the run gives up
  // Samples per second per agent the supervisor records, as the scenario asks (unset: the plan's,
  // which says what is recorded: RunPlan::record_hz).
  std::optional<double> record_hz;
};

// Where the run's DDS traffic goes.
struct TransportConfig {
  std::uint32_t domain_id = 0;
  std::string interface = "127.0.0.1";  // DDS traffic stays on this host by default
  bool shared_memory = false;
  std::uint64_t run_id = 0;  // isolates this run on a shared DDS domain (0: the launcher draws one)
  // As the scenario asks; unset: as the plan decides for the run's size and hosts (RunPlan).
  std::optional<Delivery> delivery;
  std::string keystore;  // DDS-Security keystore (an absolute path); empty: plain DDS
  std::optional<Discovery> discovery;
  // Under Delivery::kAll on loopback a sample is one datagram to the run's multicast group;
  // false: one per reader (a host whose loopback carries no multicast).
  bool multicast = true;
  // An agent reads its sockets at its tick (TickReceive) instead of with Fast DDS's threads, as
  // the scenario asks; unset: as the plan decides for the run's size (RunPlan).
  std::optional<bool> tick_receive;
};

// A scenario with every default filled in and random agents resolved: what a run actually uses.
struct RunConfig {
  std::string name = "unnamed";
  std::uint64_t seed = 1;
  std::vector<AgentSpec> agents;
  AgentConfig agent;
  JudgeConfig judge;
  TransportConfig transport;
  FaultPlan faults;
  scenario::Scenario resolved;  // the scenario as run (agents listed, defaults explicit)
  // What its size, security and hosts decide: resolve_scenario plans it for `swarm run` on one
  // host; a process elsewhere (a container, a pod) plans again for its hosts (replan).
  RunPlan plan;

  // The average of the agents' initial consensus states (their estimates of the centre): the
  // point the swarm agrees on.
  Vec3 initial_average() const;
  const AgentSpec* spec(AgentId id) const;
  // Whether any agent has a formation slot (else every agent flies to the agreed point).
  bool has_formation() const;
  std::set<AgentId> ids() const;
  // With avoidance: the agents whose slot is closer than the filter keeps agents apart to another
  // agent's slot (every agent of a rendezvous to one point). They cannot all reach their slots; the
  // record counts them arrived when they hold still. Empty without avoidance.
  std::set<AgentId> held_agents() const;
};

// The slots of a generated formation for n agents (scenario Formation.Shape as an int), centred on
// the origin, in the order the agents are assigned them (by ascending id).
std::vector<Vec3> formation_slots(int shape, int n, double spacing_m);

// n agents uniformly in a cube of side box_m, ids 1..n, from the seed. With min_separation_m > 0 a
// draw closer than that to an earlier agent is drawn again (std::runtime_error when the cube has no
// room after many draws); 0 gives the plain uniform draw.
std::vector<AgentSpec> random_agent_specs(int n, std::uint64_t seed, double box_m,
                                          double min_separation_m = 0.0);

}  // namespace qswarm
