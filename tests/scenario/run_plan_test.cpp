// The run plan, size by size: every decision that depends on a swarm's size, its security or its
// hosts, on both sides of each threshold (docs/run-plan.md has a row per threshold).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "common/scenario/run_plan.hpp"
#include "common/scenario/scenario.hpp"
#include "tests/support/plan_for.hpp"

namespace qswarm {
namespace {

// One row of the table: what a swarm of `n` agents on one host under `swarm run` gets.
struct Row {
  std::size_t n;
  bool secure;
  Delivery delivery;
  DiscoveryMode discovery;
  Routing routing;
  int participants;
  int tick_phases;
  double record_hz;
  bool spread_records;
  bool multicast;  // its state readers listen on the run's group
  double start_timeout_s;
  double announce_s;  // a participant's announcements
  int threads_nice;
};

// clang-format off
const std::vector<Row> kTable = {
  //  n   secure  delivery              discovery                    routing                    part tick rec   spread mcast start   ann   nice
  {   1, false, Delivery::kAll,        DiscoveryMode::kMulticast,    Routing::kPartitions,       2,  1, 10.0, false, true,   30.5,  1.0,  15},
  {   8, false, Delivery::kAll,        DiscoveryMode::kMulticast,    Routing::kPartitions,       9,  1, 10.0, false, true,   34.0,  1.0,  15},
  {   9, false, Delivery::kNeighbours, DiscoveryMode::kMulticast,    Routing::kPartitions,      10,  1, 10.0, false, false,  34.5,  1.0,  15},
  {  16, false, Delivery::kNeighbours, DiscoveryMode::kMulticast,    Routing::kPartitions,      17,  1, 10.0, false, false,  38.0,  1.0,  15},
  {  17, false, Delivery::kNeighbours, DiscoveryMode::kMulticast,    Routing::kPartitions,      18,  2, 10.0, false, false,  38.5,  1.0,  15},
  {  32, false, Delivery::kNeighbours, DiscoveryMode::kMulticast,    Routing::kPartitions,      33,  2, 10.0, false, false,  46.0,  1.28, 15},
  {  33, false, Delivery::kNeighbours, DiscoveryMode::kServer,       Routing::kNamedTopics,     36,  2, 10.0, false, false,  46.5,  1.32, 15},
  {  64, false, Delivery::kNeighbours, DiscoveryMode::kServer,       Routing::kNamedTopics,     67,  2, 10.0, false, false,  62.0,  2.56, 15},
  {  65, false, Delivery::kNeighbours, DiscoveryMode::kServer,       Routing::kNamedTopics,     68,  2, 10.0, true,  false,  62.5,  2.6,  15},
  { 128, false, Delivery::kNeighbours, DiscoveryMode::kServer,       Routing::kNamedTopics,    131,  2, 10.0, true,  false,  94.0,  5.12, 15},
  { 129, false, Delivery::kNeighbours, DiscoveryMode::kServer,       Routing::kRegionTopics,   131,  2, 50.0 / 5.0, true, false, 94.5, 5.16, 15},
  { 512, false, Delivery::kNeighbours, DiscoveryMode::kServer,       Routing::kRegionTopics,   514,  2, 2.5,  true,  false, 286.0, 20.48, 15},
  // Secure: never a Discovery Server (Fast DDS 2.9 has no secure one), discovery by unicast within
  // the run's block, no multicast group, Fast DDS's threads at the tick's priority.
  {   1, true,  Delivery::kAll,        DiscoveryMode::kUnicastBlock, Routing::kPartitions,       2,  1, 10.0, false, false,  30.5,  1.0,   0},
  {   8, true,  Delivery::kAll,        DiscoveryMode::kUnicastBlock, Routing::kPartitions,       9,  1, 10.0, false, false,  34.0,  1.0,   0},
  {   9, true,  Delivery::kNeighbours, DiscoveryMode::kUnicastBlock, Routing::kPartitions,      10,  1, 10.0, false, false,  34.5,  1.0,   0},
  {  16, true,  Delivery::kNeighbours, DiscoveryMode::kUnicastBlock, Routing::kPartitions,      17,  1, 10.0, false, false,  38.0,  1.0,   0},
  {  17, true,  Delivery::kNeighbours, DiscoveryMode::kUnicastBlock, Routing::kPartitions,      18,  2, 10.0, false, false,  38.5,  1.0,   0},
  {  32, true,  Delivery::kNeighbours, DiscoveryMode::kUnicastBlock, Routing::kPartitions,      33,  2, 10.0, false, false,  46.0,  1.28,  0},
  {  33, true,  Delivery::kNeighbours, DiscoveryMode::kUnicastBlock, Routing::kPartitions,      34,  2, 10.0, false, false,  46.5,  1.32,  0},
  {  64, true,  Delivery::kNeighbours, DiscoveryMode::kUnicastBlock, Routing::kPartitions,      65,  2, 10.0, false, false,  62.0,  2.56,  0},
  {  65, true,  Delivery::kNeighbours, DiscoveryMode::kUnicastBlock, Routing::kPartitions,      66,  2, 10.0, true,  false,  62.5,  2.6,   0},
  { 128, true,  Delivery::kNeighbours, DiscoveryMode::kUnicastBlock, Routing::kPartitions,     129,  2, 10.0, true,  false,  94.0,  5.12,  0},
  { 129, true,  Delivery::kNeighbours, DiscoveryMode::kUnicastBlock, Routing::kPartitions,     130,  2, 10.0, true,  false,  94.5,  5.16,  0},
  { 512, true,  Delivery::kNeighbours, DiscoveryMode::kUnicastBlock, Routing::kPartitions,     513,  2, 2.5,  true,  false, 286.0, 20.48,  0},
};
// clang-format on

TEST(RunPlan, EveryThresholdOnBothSidesPlainAndSecure) {
  for (const Row& r : kTable) {
    const std::string at = std::to_string(r.n) + (r.secure ? " secure" : " plain");
    const RunPlan p = test::plan_for(r.n, r.secure);
    EXPECT_EQ(p.agents, r.n) << at;
    EXPECT_EQ(p.secure, r.secure) << at;
    EXPECT_EQ(p.delivery, r.delivery) << at;
    EXPECT_EQ(p.discovery, r.discovery) << at;
    EXPECT_EQ(p.own_server, r.discovery == DiscoveryMode::kServer) << at;
    // Two, so that one relays if the other hangs, up to 128 agents; past it two never finished.
    EXPECT_EQ(p.own_servers, !p.own_server ? 0 : r.n <= 128 ? 2 : 1) << at;
    EXPECT_EQ(p.routing, r.routing) << at;
    EXPECT_EQ(p.participants, r.participants) << at;
    EXPECT_EQ(p.tick_phases, r.tick_phases) << at;
    EXPECT_EQ(p.tick_receive, r.n <= 128) << at;  // receive at the tick up to 128 agents
    EXPECT_DOUBLE_EQ(p.record_hz, r.record_hz) << at;
    EXPECT_EQ(p.record_every, static_cast<std::uint32_t>(std::lround(50.0 / r.record_hz))) << at;
    EXPECT_EQ(p.spread_records, r.spread_records) << at;
    EXPECT_EQ(p.multicast_group.empty(), !r.multicast) << at;
    EXPECT_DOUBLE_EQ(p.start_timeout_s, r.start_timeout_s) << at;
    EXPECT_DOUBLE_EQ(p.join_timeout_s, r.start_timeout_s + 10.0) << at;
    EXPECT_DOUBLE_EQ(p.participant_announce_period_s, r.announce_s) << at;
    EXPECT_EQ(p.dds_threads_nice, r.threads_nice) << at;
    EXPECT_EQ(p.reader_agents, std::max<int>(static_cast<int>(r.n), 16)) << at;
    EXPECT_EQ(p.claim_capacity, 2 * r.n + 16) << at;
    EXPECT_DOUBLE_EQ(p.claim_timeout_s, 60.0 + 4.0 * static_cast<double>(r.n)) << at;
    EXPECT_DOUBLE_EQ(p.claim_period_s, 0.1 * std::max(1.0, static_cast<double>(r.n) / 6.0)) << at;
    // The supervisor keeps a silent agent three record periods at least (the neighbour timeout,
    // 1 s, otherwise).
    EXPECT_DOUBLE_EQ(p.presence_timeout_s, std::max(1.0, 3.0 / r.record_hz)) << at;
    // The barrier: 5 ms per 8 agents when ready, 50 ms per 8 past 8 while waiting, ten times
    // slower when secure, and a beacon at least every half presence timeout.
    const double n = static_cast<double>(r.n), slow = r.secure ? 10.0 : 1.0;
    const double ready = 0.005 * std::max(1.0, n / 8.0) * slow;
    const double waiting =
        std::min((r.n <= 8 ? 0.005 * std::max(1.0, n / 8.0) : 0.05 * n / 8.0) * slow,
                 0.5 * p.presence_timeout_s);
    EXPECT_DOUBLE_EQ(p.barrier_waiting_period_s, waiting) << at;
    EXPECT_DOUBLE_EQ(p.barrier_announce_period_s, std::min(ready, waiting)) << at;
    // Stops: an agent after twice the flight and 30 s, the launcher after the flight and room for
    // the start.
    EXPECT_DOUBLE_EQ(p.agent_wall_limit_s, 2.0 * 60.0 + 30.0) << at;
    EXPECT_DOUBLE_EQ(p.launcher_wall_limit_s, 60.0 + std::max(120.0, r.start_timeout_s + 30.0))
        << at;
  }
}

TEST(RunPlan, TheScenarioOverridesWhatItSetsAndTheTimeScaleStretchesTheWallLimits) {
  const RunConfig asked = resolve_scenario(
      parse_scenario_text("random_agents { count: 64 }\n"
                          "transport { delivery: ALL discovery: SIMPLE multicast: false }\n"
                          "record { rate_hz: 25 }\n",
                          "s"));
  EXPECT_EQ(asked.plan.delivery, Delivery::kAll);
  EXPECT_EQ(asked.plan.discovery, DiscoveryMode::kMulticast);
  EXPECT_EQ(asked.plan.multicast_group, "");
  EXPECT_DOUBLE_EQ(asked.plan.record_hz, 25.0);
  EXPECT_EQ(asked.plan.record_every, 2u);
  EXPECT_TRUE(resolve_scenario(parse_scenario_text("random_agents { count: 200 }\n"
                                                   "transport { receive: TICK }\n",
                                                   "s"))
                  .plan.tick_receive);
  EXPECT_FALSE(resolve_scenario(parse_scenario_text("random_agents { count: 8 }\n"
                                                    "transport { receive: THREADS }\n",
                                                    "s"))
                   .plan.tick_receive);
  // The scenario as run says what the plan decided, so a process that resolves it again agrees.
  EXPECT_EQ(asked.resolved.transport().delivery(), scenario::Transport::ALL);
  EXPECT_DOUBLE_EQ(asked.resolved.record().rate_hz(), 25.0);
  const RunConfig again = resolve_scenario(asked.resolved);
  EXPECT_EQ(again.plan.record_every, asked.plan.record_every);
  EXPECT_EQ(again.plan.routing, asked.plan.routing);

  Hosts slow;
  slow.time_scale = 0.5;
  const RunPlan p = plan_run(asked, slow);
  EXPECT_DOUBLE_EQ(p.agent_wall_limit_s, 2.0 * 120.0 + 30.0);
  // A beacon at least every half presence timeout of wall time: at half speed, twice as long.
  EXPECT_DOUBLE_EQ(p.barrier_waiting_period_s, std::min(0.05 * 64 / 8.0, 0.5 * 1.0 / 0.5));
}

TEST(RunPlan, TheHostsDecideHowProcessesFindEachOther) {
  const std::size_t n = 64;
  // A compose replica (no launcher): simple discovery unless given a server, whatever the size.
  Hosts alone;
  alone.launcher = false;
  EXPECT_EQ(test::plan_for(n, false, alone).discovery, DiscoveryMode::kMulticast);
  EXPECT_FALSE(test::plan_for(n, false, alone).own_server);
  Hosts given = alone;
  given.discovery_server = "discovery:11811";
  const RunPlan served = test::plan_for(n, false, given);
  EXPECT_EQ(served.discovery, DiscoveryMode::kServer);
  EXPECT_FALSE(served.own_server);
  EXPECT_EQ(served.participants, 65);
  EXPECT_EQ(served.routing, Routing::kNamedTopics);
  // Found by host name: one participant per host, never the multicast group.
  Hosts peers = alone;
  peers.peer_hosts = true;
  peers.interface.clear();
  const RunPlan found = test::plan_for(4, true, peers);
  EXPECT_EQ(found.discovery, DiscoveryMode::kPeerHosts);
  EXPECT_DOUBLE_EQ(found.peer_hosts_wait_s, 120.0);
  EXPECT_EQ(found.peer_host_addresses, 5u);  // a container per participant
  // Hosts running a block of ids each: one address per name listed.
  Hosts blocks = peers;
  blocks.peer_host_names = 3;
  blocks.unicast_block = std::make_pair(0, 9);
  EXPECT_EQ(test::plan_for(24, true, blocks).peer_host_addresses, 3u);
  EXPECT_EQ(found.multicast_group, "");
  // Peers beside a server, or a secure run through one, are refused naming what was asked.
  peers.discovery_server = "discovery:11811";
  try {
    test::plan_for(4, false, peers);
    ADD_FAILURE() << "peer hosts beside a server were planned";
  } catch (const ScenarioError& e) {
    EXPECT_NE(std::string(e.what()).find("--peer-hosts"), std::string::npos) << e.what();
  }
  try {
    test::plan_for(4, true, given);
    ADD_FAILURE() << "a secure run through a Discovery Server was planned";
  } catch (const ScenarioError& e) {
    EXPECT_NE(std::string(e.what()).find("--discovery-server"), std::string::npos) << e.what();
  }
  // A block to discover by unicast and a server beside it: one or the other.
  Hosts both = given;
  both.unicast_block = std::pair{10, 4};
  EXPECT_THROW(test::plan_for(4, false, both), ScenarioError);
  // A secure swarm in a container (every interface) has no block of one address: multicast.
  Hosts container;
  container.interface.clear();
  EXPECT_EQ(test::plan_for(8, true, container).discovery, DiscoveryMode::kMulticast);
  // Off loopback, no multicast group for the state stream.
  Hosts lan;
  lan.interface = "10.1.2.3";
  EXPECT_EQ(test::plan_for(8, false, lan).multicast_group, "");
}

TEST(RunPlan, TheBlockNamesEveryProcessOnce) {
  const RunPlan p = test::plan_for(33);  // with its own Discovery Server
  ASSERT_TRUE(p.own_server);
  EXPECT_EQ(p.supervisor_participant(100), 100);
  EXPECT_EQ(p.agent_participant(100, 0), 101);
  EXPECT_EQ(p.agent_participant(100, 32), 133);
  EXPECT_EQ(p.server_participant(100, 0), 134);
  EXPECT_EQ(p.server_participant(100, 1), 135);
  EXPECT_EQ(p.server_participant(100, 1), 100 + p.participants - 1);
  EXPECT_EQ(to_proto(p).own_servers(), 2);
}

TEST(RunPlan, OnlyTheRunsOwnDiscoveryServerRunsAtAHigherPriority) {
  const RunPlan served = test::plan_for(33);
  ASSERT_TRUE(served.own_server);
  EXPECT_EQ(served.server_nice, -10);
  EXPECT_EQ(to_proto(served).server_nice(), -10);
  EXPECT_EQ(test::plan_for(32).server_nice, 0);        // simple discovery: no server
  EXPECT_EQ(test::plan_for(33, true).server_nice, 0);  // secure: never a server (W8)
}

TEST(RunPlan, TheSupervisorHearsAheadOfTheTicksOnlyWhileItsLoadIsSmall) {
  EXPECT_EQ(test::plan_for(1).supervisor_threads_nice, -10);
  EXPECT_EQ(test::plan_for(32).supervisor_threads_nice, -10);
  EXPECT_EQ(to_proto(test::plan_for(32)).supervisor_threads_nice(), -10);
  EXPECT_EQ(test::plan_for(33).supervisor_threads_nice, 0);       // 330 records a second and up
  EXPECT_EQ(test::plan_for(8, true).supervisor_threads_nice, 0);  // secure: threads race (W2)
}

TEST(RunPlan, ItsRecordSaysEveryDecisionAndTheNamesOnTheWire) {
  const plan::RunPlan o = to_proto(test::plan_for(129), 40);
  EXPECT_EQ(o.agents(), 129u);
  EXPECT_EQ(o.routing(), "region-topics");
  EXPECT_EQ(o.discovery(), "server");
  EXPECT_EQ(o.delivery(), "neighbours");
  EXPECT_EQ(o.participant_base(), 40);
  EXPECT_EQ(o.state_topic(), "qswarm/agent_state");
  EXPECT_EQ(o.run_partition(), "qswarm-run-0000000000000001");
  EXPECT_EQ(o.record_partition(), "qswarm-record-0000000000000001");
  EXPECT_EQ(o.tick_phases(), 2);
}

}  // namespace
}  // namespace qswarm
