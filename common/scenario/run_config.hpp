#pragma once

#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include "common/core/agent.hpp"
#include "common/core/airframe.hpp"
#include "common/core/avoidance.hpp"
#include "common/core/tracking_controller.hpp"
#include "common/core/update_law.hpp"
#include "common/scenario/fault_plan.hpp"
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
  AgentMode mode = AgentMode::kParticle;
  LawConfig law;
  double physics_hz = 500.0;
  double consensus_hz = 50.0;
  Airframe airframe;
  TrackingGains gains;
  double reference_speed_mps = 3.0;   // how fast the tracked reference may move
  double reference_accel_mps2 = 2.0;  // and accelerate
  // Collision avoidance (enabled: quadcopters filter their references) and the safe distance the
  // record judges separation by, in every mode.
  AvoidanceConfig avoidance;
  double neighbor_timeout_s = 1.0;  // a neighbour silent this long (simulated) leaves the graph
  // Physics steps per consensus tick (the resolver refuses rates that do not divide).
  int steps_per_tick() const;
};

// How the record judges the run.
struct JudgeConfig {
  double tolerance_m = 0.01;  // agreed: every state within this of the mean
  double hold_s = 1.0;        // for this long
  double duration_s = 60.0;   // simulated seconds before the run gives up
  // Samples per second per agent the supervisor records (each agent sends every record_every()-th
  // sample to it); at most the consensus rate.
  double record_hz = 10.0;
};

// Which samples an agent is sent: those of the agents that can be its neighbours (the default), or
// everyone's.
enum class Delivery { kNeighbours, kAll, kReach };
// How a run's participants discover each other (scenario Transport.Discovery).
enum class Discovery { kSimple, kServer };

// Where the run's DDS traffic goes.
struct TransportConfig {
  std::uint32_t domain_id = 0;
  std::string interface = "127.0.0.1";  // DDS traffic stays on this host by default
  bool shared_memory = false;
  std::uint64_t run_id = 0;  // isolates this run on a shared DDS domain (0: the launcher draws one)
  Delivery delivery = Delivery::kNeighbours;
  std::string keystore;  // DDS-Security keystore (an absolute path); empty: plain DDS
  Discovery discovery = Discovery::kSimple;
  // Under Delivery::kAll on loopback a sample is one datagram to the run's multicast group;
  // false: one per reader (a host whose loopback carries no multicast).
  bool multicast = true;
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
  // Wall seconds an agent waits at the start barrier before it starts anyway, and the supervisor
  // for the first running agent: discovery grows with the swarm (100 agents on 2 cores took 25 s),
  // so 30 s plus half a second per agent.
  double start_timeout_s() const { return 30.0 + 0.5 * static_cast<double>(agents.size()); }
  // Every how many of its samples an agent sends one to the supervisor: the consensus rate over
  // the record rate, rounded, at least 1.
  std::uint32_t record_every() const;
  // How long an agent the supervisor hears nothing of stays present (swarm seconds): three record
  // periods at least, so that a record rate lowered for a large swarm (2.5 Hz at 512 agents) does
  // not make two lost records a departure.
  double presence_timeout_s() const;
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
