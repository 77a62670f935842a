// Traffic that follows the graph: an agent hears the agents that can be its neighbours soon and no
// others (Neighbourhood), and no agent misses a neighbour it should have had: in-process runs give
// the same graph, edge for edge and tick for tick, as the same runs with everyone hearing everyone.
#include <fnmatch.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "common/runtime/neighbourhood.hpp"
#include "common/scenario/scenario.hpp"
#include "common/sim/in_process_swarm.hpp"

namespace qswarm {
namespace {

// Delivery REACH asked for (the place filter these tests are about; small swarms hear everyone
// by default).
RunConfig load(const std::string& text, const std::string& extra = "") {
  const bool own = extra.find("transport") != std::string::npos;
  return resolve_scenario(
      parse_scenario_text(text + extra + (own ? "" : "\ntransport { delivery: REACH }\n"), "s"));
}

TEST(Neighbourhood, CellsCoverTheLinkReachAndIdsCoverTheGraph) {
  // Radio range 4.5 m (+ 0.5 hysteresis) and a margin of 1.25 m: cells of (5 + 2.5) / 2 m in
  // physical space.
  const std::string four =
      "agents { id: 1 position { x: 0 y: 0 z: 0 } }\n"
      "agents { id: 2 position { x: 6 y: 0 z: 0 } }\n"
      "agents { id: 3 position { x: 10 y: 0 z: 0 } }\n"
      "agents { id: 4 position { x: 40 y: 0 z: 0 } }\n"
      "agents { id: 5 position { x: 0 y: 12 z: 0 } }\n"
      "topology { policy: RANGE threshold_m: 4.5 hysteresis_m: 0.5 edges { a: 1 b: 4 } }\n";
  // Delivery NEIGHBOURS: the cells and the names, and everything they bring (3, 10 m from 1, is
  // in the cells around it; 5, 12 m from it, is three cells away, where cells a reach wide would
  // have brought it too).
  const RunConfig cells = load(four, "transport { delivery: NEIGHBOURS }\n");
  const Interest by_cell = Neighbourhood(cells, 1).update(Vec3(0, 0, 0), Vec3(0, 0, 0), {});
  EXPECT_EQ(by_cell.publish, (std::vector<std::string>{"a1", "p0.0.0"}));
  EXPECT_EQ(by_cell.subscribe.size(), 125u + 1u);  // 5 x 5 x 5 cells, the listed edge's agent
  EXPECT_TRUE(by_cell.near.empty());
  EXPECT_EQ(Neighbourhood::heard_at_start(cells, 1), (std::set<AgentId>{2, 3, 4}));
  // Delivery REACH: the same cells, an inbox, and a box about itself.
  const RunConfig rc = load(four);
  Neighbourhood n1(rc, 1);
  const Interest in = n1.update(Vec3(0, 0, 0), Vec3(0, 0, 0), {});
  EXPECT_EQ(in.publish, (std::vector<std::string>{"a1", "p0.0.0"}));
  EXPECT_EQ(in.subscribe.size(), 125u + 1u + 1u);  // the cells, the listed edge's agent, its inbox
  EXPECT_TRUE(std::binary_search(in.subscribe.begin(), in.subscribe.end(), "in1"));
  // Of what the cells bring, it hears the reach plus a margin (5 + 1.25 m) of a box about itself
  // (half a margin on each side).
  ASSERT_EQ(in.near.size(), 1u);
  EXPECT_EQ(in.near[0], (Reach{'p', Vec3::Constant(-0.625), Vec3::Constant(0.625), 6.25}));
  // Who hears whom at the start: within the reach of each other (not 3, 10 m from 1, though in
  // the cells around it), and the listed edge both ways.
  EXPECT_EQ(Neighbourhood::heard_at_start(rc, 1), (std::set<AgentId>{2, 4}));
  EXPECT_EQ(Neighbourhood::heard_at_start(rc, 2), (std::set<AgentId>{1, 3}));
  EXPECT_EQ(Neighbourhood::heard_at_start(rc, 4), (std::set<AgentId>{1}));
  // Under radio range a link moves nothing: its samples name the other end, which hears them
  // wherever it is while the cells bring them (Interest::hears); under sticky proximity it is
  // heard by name, however far.
  EXPECT_EQ(n1.update(Vec3(0, 0, 0), Vec3(0, 0, 0), {3}), in);
  EXPECT_FALSE(Interest::hears(in, in, Vec3(100, 0, 0), Vec3(100, 0, 0)));
  EXPECT_TRUE(Interest::hears(in, in, Vec3(100, 0, 0), Vec3(100, 0, 0), /*bonded=*/true));
  const RunConfig sticky = load(
      "agents { id: 1 } agents { id: 3 position { x: 100 } }\n"
      "topology { policy: STICKY_PROXIMITY threshold_m: 5 }\n");
  const Interest linked = Neighbourhood(sticky, 1).update(Vec3(0, 0, 0), Vec3(0, 0, 0), {3});
  EXPECT_TRUE(std::binary_search(linked.subscribe.begin(), linked.subscribe.end(), "a3"));
  // Everyone hears everyone under delivery ALL: the empty interest.
  const RunConfig all = load("agents { id: 1 } agents { id: 2 position { x: 100 } }\n",
                             "transport { delivery: ALL }\n");
  EXPECT_TRUE(Neighbourhood(all, 1).whole_run());
  EXPECT_EQ(Neighbourhood::heard_at_start(all, 1), (std::set<AgentId>{2}));
  // Unset, a swarm of up to 8 hears everyone (and starts together); a larger one its neighbours.
  EXPECT_EQ(resolve_scenario(parse_scenario_text("random_agents { count: 8 }", "s")).plan.delivery,
            Delivery::kAll);
  EXPECT_EQ(resolve_scenario(parse_scenario_text("random_agents { count: 9 }", "s")).plan.delivery,
            Delivery::kNeighbours);
}

TEST(Neighbourhood, EveryPairWithinTheReachPlusMarginHearsEachOtherAsTheyWander) {
  const RunConfig rc = load(
      "agents { id: 1 } agents { id: 2 position { x: 1 } }\n"
      "topology { policy: RANGE threshold_m: 4.5 hysteresis_m: 0.5 }\n");
  const double reach = 5.0 + Neighbourhood::margin_m(5.0);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> step(-0.4, 0.4), u(-30.0, 30.0);
  int close = 0, cell_moves = 0, box_moves = 0;
  for (int walk = 0; walk < 200; ++walk) {
    // Two agents wander (each keeping its cell, and its box, until half a margin outside it),
    // often close, 0.35 m a step on average.
    Neighbourhood a(rc, 1), b(rc, 2);
    Vec3 pa(u(rng), u(rng), u(rng)), pb = pa + Vec3(step(rng), step(rng), step(rng)) * 10.0;
    Interest last_a;
    for (int k = 0; k < 400; ++k) {
      pa += Vec3(step(rng), step(rng), step(rng));
      pb += Vec3(step(rng), step(rng), step(rng)) + 0.02 * (pa - pb);  // drawn to each other
      const Interest ia = a.update(pa, pa, {}), ib = b.update(pb, pb, {});
      cell_moves += ia.publish != last_a.publish || ia.subscribe != last_a.subscribe;
      box_moves += ia.near != last_a.near;
      last_a = ia;
      if ((pa - pb).norm() > reach) continue;
      ++close;
      ASSERT_TRUE(Interest::hears(ib, ia, pa, pa) && Interest::hears(ia, ib, pb, pb))
          << "walk " << walk << " step " << k << ": " << (pa - pb).norm() << " m apart";
    }
  }
  EXPECT_GT(close, 20000);  // the property was tested, not skipped
  // Neither flaps at every step: cells move rarely, the box once about 0.6 m of travel.
  EXPECT_LT(cell_moves, 200 * 400 / 5);
  EXPECT_LT(box_moves, 200 * 400 / 3);
}

TEST(Neighbourhood, TheWorstCaseAcrossCellBordersStillHearsWithinTheReachPlusMargin) {
  // Agent 1 comes from the left and stops at x; agent 2 comes from the right and stops just within
  // the reach plus margin of it: each keeps the cell it came from as long as it may, the farthest
  // apart their cells can be.
  const RunConfig rc = load(
      "agents { id: 1 } agents { id: 2 position { x: 1 } }\n"
      "topology { policy: RANGE threshold_m: 4.5 hysteresis_m: 0.5 }\n");
  const double d = 5.0 + Neighbourhood::margin_m(5.0) - 1e-6;
  for (double x = 0.0; x < 20.0; x += 0.05) {
    Neighbourhood a(rc, 1), b(rc, 2);
    Interest ia, ib;
    for (double at = x - 10.0; at <= x; at += 0.05) ia = a.update(Vec3(at, 0, 0), Vec3::Zero(), {});
    ia = a.update(Vec3(x, 0, 0), Vec3::Zero(), {});
    for (double at = x + d + 10.0; at >= x + d; at -= 0.05)
      ib = b.update(Vec3(at, 0, 0), Vec3::Zero(), {});
    ib = b.update(Vec3(x + d, 0, 0), Vec3::Zero(), {});
    ASSERT_TRUE(Interest::hears(ib, ia, Vec3::Zero(), Vec3(x, 0, 0)) &&
                Interest::hears(ia, ib, Vec3::Zero(), Vec3(x + d, 0, 0)))
        << "at x = " << x;
  }
}

// What a listener's cells become on the wire: patterns that fnmatch (as Fast DDS matches
// partitions) exactly the names its cells' writers publish under, however the cells lie about
// the borders of the hex digits and zero.
TEST(Neighbourhood, AListenersCellPatternsMatchExactlyItsCellsNames) {
  const auto cell = [](char tag, int x, int y, int z) {
    return tag + std::to_string(x) + "." + std::to_string(y) + "." + std::to_string(z);
  };
  const auto wire = [](const std::string& name) {
    const std::vector<std::string> w = dds_partition_names({name}, /*patterns=*/false);
    EXPECT_EQ(w.size(), 1u);
    return w.front();
  };
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<int> at(-40, 40), drop(0, 9);
  for (int trial = 0; trial < 300; ++trial) {
    const int x0 = at(rng), y0 = at(rng), z0 = at(rng);
    const bool box = trial % 3 != 0;  // every third set has holes: named cell by cell
    std::vector<std::string> names{"a7", "in3", "c"};
    std::set<std::string> mine;
    for (int dx = -Neighbourhood::kSpan; dx <= Neighbourhood::kSpan; ++dx)
      for (int dy = -Neighbourhood::kSpan; dy <= Neighbourhood::kSpan; ++dy)
        for (int dz = -Neighbourhood::kSpan; dz <= Neighbourhood::kSpan; ++dz) {
          if (!box && drop(rng) == 0) continue;
          for (const char tag : {'p', 'q'}) {
            names.push_back(cell(tag, x0 + dx, y0 + dy, z0 + dz));
            mine.insert(names.back());
          }
        }
    const std::vector<std::string> patterns = dds_partition_names(names, /*patterns=*/true);
    for (const char* other : {"a7", "in3", "c"})
      EXPECT_EQ(std::count(patterns.begin(), patterns.end(), other), 1) << other;
    if (box) {
      EXPECT_LE(patterns.size(), 3u + 2u * 8u);  // each space's box: at most 8 patterns
    }
    for (int x = x0 - 4; x <= x0 + 4; ++x)
      for (int y = y0 - 4; y <= y0 + 4; ++y)
        for (int z = z0 - 4; z <= z0 + 4; ++z)
          for (const char tag : {'p', 'q'}) {
            const std::string name = cell(tag, x, y, z), published = wire(name);
            const bool matched = std::any_of(patterns.begin(), patterns.end(), [&](auto& p) {
              return fnmatch(p.c_str(), published.c_str(), FNM_NOESCAPE) == 0 ||
                     fnmatch(published.c_str(), p.c_str(), FNM_NOESCAPE) == 0;
            });
            ASSERT_EQ(matched, mine.count(name) == 1) << name << " as " << published;
          }
  }
  // Names that are not cells, or cells out of range, pass as they are.
  EXPECT_EQ(dds_partition_names({"p1.2", "p1.2.3x", "q1.2.99999999999", "a3"}, true),
            (std::vector<std::string>{"a3", "p1.2", "p1.2.3x", "q1.2.99999999999"}));
  EXPECT_EQ(wire("p-1.0.15"), "p7fffffff.80000000.8000000f");
}

// Regions are blocks of kRegionCells cells on each axis, counted down from 0 for negative
// indices; a listener's box of 2 kSpan + 1 cells touches at most two of them on each axis, and
// the cells about a cell are named as Neighbourhood names them.
TEST(Neighbourhood, RegionsAreBlocksOfCellsThatABoxTouchesAtMostTwoOfPerAxis) {
  EXPECT_EQ(region_of_cell("p0.0.0"), "rp0.0.0");
  EXPECT_EQ(region_of_cell("p4.-1.5"), "rp0.-1.1");
  EXPECT_EQ(region_of_cell("q-5.-6.-10"), "rq-1.-2.-2");
  EXPECT_EQ(region_of_cell("p-2147483648.2147483647.0"), "rp-429496730.429496729.0");
  for (const std::string bad : {"a3", "in3", "c.0.0.0", "p1.2", "p1.2.3x", "q1.2.99999999999"}) {
    EXPECT_FALSE(region_of_cell(bad)) << bad;
    EXPECT_TRUE(cells_about(bad, 1).empty()) << bad;
  }
  const std::vector<std::string> about = cells_about("p-1.0.7", 1);
  ASSERT_EQ(about.size(), 27u);
  EXPECT_EQ(about.front(), "p-2.-1.6");
  EXPECT_EQ(about[13], "p-1.0.7");
  EXPECT_EQ(about.back(), "p0.1.8");
  static_assert(kRegionCells >= 2 * Neighbourhood::kSpan + 1);
  for (int x = -12; x <= 12; ++x) {
    std::set<std::string> regions;
    for (const std::string& c :
         cells_about("p" + std::to_string(x) + ".3.-4", Neighbourhood::kSpan))
      regions.insert(*region_of_cell(c));
    EXPECT_LE(regions.size(), 8u) << x;
    EXPECT_GE(regions.size(), 4u) << x;  // y 1..5 and z -6..-2 straddle two regions each
  }
}

// A place that is not a number (an agent whose samples are refused anyway) lies in the origin's
// cell, not in one cast from NaN.
TEST(Neighbourhood, APlaceThatIsNotANumberLiesInTheOriginsCell) {
  const RunConfig rc = load(
      "agents { id: 1 } agents { id: 2 position { x: 1 } }\n"
      "topology { policy: RANGE threshold_m: 4.5 hysteresis_m: 0.5 }\n");
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(Neighbourhood(rc, 1).update(Vec3(nan, 0, -nan), Vec3::Zero(), {}).publish,
            (std::vector<std::string>{"a1", "p0.0.0"}));
}

TEST(Neighbourhood, APeerLeftToSettleWithIsPushedToItsInboxUntilSettled) {
  const RunConfig rc = load(
      "agents { id: 1 } agents { id: 2 position { x: 1 } } agents { id: 3 position { x: 2 } }\n"
      "topology { policy: RANGE threshold_m: 4.5 hysteresis_m: 0.5 }\n");
  Neighbourhood n(rc, 1);
  const auto pushes = [](const Interest& in, AgentId id) {
    return std::binary_search(in.publish.begin(), in.publish.end(), inbox_partition(id));
  };
  const Vec3 at = Vec3::Zero();
  // A link just ended and is settling while the peer is heard: it usually settles within a tick
  // or two, and pushing would move the writer's partitions for nothing.
  Interest in = n.update(at, at, {}, {{2, true}});
  EXPECT_FALSE(pushes(in, 2));
  in = n.update(at, at, {}, {{2, true}});
  EXPECT_FALSE(pushes(in, 2));
  // Still open on the third tick, or the peer fell silent: push, until settled.
  in = n.update(at, at, {}, {{2, true}, {3, false}});
  EXPECT_TRUE(pushes(in, 2));
  EXPECT_TRUE(pushes(in, 3));
  in = n.update(at, at, {}, {{2, true}, {3, true}});  // heard again: no flapping
  EXPECT_TRUE(pushes(in, 3));
  in = n.update(at, at, {}, {});
  EXPECT_FALSE(pushes(in, 2) || pushes(in, 3));
  // What the inbox brings passes like what cells bring: a sample far from the listener's reach
  // passes only if it names the listener (a bond), not by its name alone.
  Interest far = Neighbourhood(rc, 2).update(Vec3(50, 0, 0), Vec3(50, 0, 0), {}, {{1, false}});
  ASSERT_TRUE(pushes(far, 1));
  EXPECT_FALSE(Interest::hears(in, far, Vec3(50, 0, 0), Vec3(50, 0, 0)));
  EXPECT_TRUE(Interest::hears(in, far, Vec3(50, 0, 0), Vec3(50, 0, 0), /*bonded=*/true));
  EXPECT_EQ(inbox_of_partition("in12"), AgentId{12});
  EXPECT_FALSE(inbox_of_partition("in012") || inbox_of_partition("a12") ||
               inbox_of_partition("in"));
  EXPECT_FALSE(agent_of_partition("in12"));
}

TEST(Neighbourhood, AFixedGraphHearsExactlyItsEdgesAndStartPeersLeaveOutLateJoiners) {
  const RunConfig rc = load(
      "agents { id: 1 } agents { id: 2 } agents { id: 3 } agents { id: 4 }\n"
      "topology { policy: FIXED edges { a: 1 b: 2 } edges { a: 2 b: 3 } edges { a: 3 b: 4 } }\n"
      "faults { late_join { agent: 3 at_s: 2 } }\n");
  EXPECT_EQ(Neighbourhood(rc, 2).update(Vec3::Zero(), Vec3::Zero(), {}).subscribe,
            (std::vector<std::string>{"a1", "a3"}));
  EXPECT_EQ(start_peers(rc, 2), (std::set<AgentId>{1}));  // 3 joins late
  EXPECT_EQ(start_peers(rc, 4), (std::set<AgentId>{}));
}

// The edge_list column of graph.csv, row by row (found by its header: columns were added after it).
std::vector<std::string> edge_lists(const RunDir& dir) {
  std::ifstream in(dir.graph());
  const auto cells = [](const std::string& row) {
    std::vector<std::string> out(1);
    bool quoted = false;
    for (const char c : row) {
      if (c == '"') {
        quoted = !quoted;
      } else if (c == ',' && !quoted) {
        out.emplace_back();
      } else {
        out.back() += c;
      }
    }
    return out;
  };
  std::string row;
  std::getline(in, row);
  const std::vector<std::string> header = cells(row);
  const auto col = static_cast<std::size_t>(std::find(header.begin(), header.end(), "edge_list") -
                                            header.begin());
  EXPECT_LT(col, header.size()) << "graph.csv has no edge_list column";
  std::vector<std::string> out;
  while (std::getline(in, row)) {
    const std::vector<std::string> c = cells(row);
    out.push_back(col < c.size() ? c[col] : "?");
  }
  return out;
}

RunDir fresh(const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() /
      ("qswarm-neighbourhood-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  return RunDir::claim(dir.string(), name, "t");
}

// The same run three times, hearing everyone, neighbours by cell, and by reach: the graph the
// recorder saw, row by row, must be the same.
void same_graph_both_ways(const std::string& scenario, double wall_s) {
  std::vector<std::string> graphs[3];
  int k = 0;
  for (const char* delivery : {"ALL", "NEIGHBOURS", "REACH"}) {
    const RunConfig rc = load(scenario, std::string("transport { delivery: ") + delivery + " }\n");
    const RunDir dir = fresh(delivery);
    {
      InProcessSwarm swarm(rc, 1.0, dir);
      swarm.run_until_wall(wall_s);
      swarm.run_recorded(wall_s);
    }
    graphs[k++] = edge_lists(dir);
    std::filesystem::remove_all(dir.path());
  }
  ASSERT_GT(graphs[0].size(), 10u);
  // The edge sets one after the other: an agent that hears nobody at the start (nobody within its
  // reach) leaves its start barrier at once instead of with everyone, which shifts the rows' times
  // but must not change a single edge.
  for (auto& g : graphs) g.erase(std::unique(g.begin(), g.end()), g.end());
  EXPECT_GT(graphs[0].size(), 5u);
  EXPECT_EQ(graphs[0], graphs[1]);
  EXPECT_EQ(graphs[0], graphs[2]);
}

TEST(NeighbourDelivery, ThePapersTimeVaryingGraphIsTheSameAsWhenEveryoneHearsEveryone) {
  same_graph_both_ways(
      "agents { id: 1 position { x: 16 y: 5 z: 36 } }\n"
      "agents { id: 2 position { x: 19 y: 19 z: 29 } }\n"
      "agents { id: 3 position { x: 12 y: 16 z: 33 } }\n"
      "agents { id: 4 position { x: 14 y: 1 z: 26 } }\n"
      "weight { policy: DISTANCE } topology { policy: STICKY_PROXIMITY threshold_m: 12.5 }\n"
      "convergence { tolerance_m: 0.008 hold_s: 0.5 } duration_s: 120 seed: 1\n",
      25.0);
}

TEST(NeighbourDelivery, AThirtyTwoAgentFormationOverRadioRangeHasTheSameGraphAsAllToAll) {
  // Spread over many cells (6.25 m each) and flying across them into a lattice.
  same_graph_both_ways(
      "random_agents { count: 32 box_m: 24 }\n"
      "weight { policy: UNWEIGHTED } topology { policy: RANGE threshold_m: 4.5 hysteresis_m: 0.5 "
      "}\n"
      "formation { shape: LATTICE spacing_m: 3 } convergence { tolerance_m: 0.005 hold_s: 1 }\n"
      "duration_s: 60 seed: 3\n",
      20.0);
}

}  // namespace
}  // namespace qswarm
