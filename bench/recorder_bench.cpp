// What the supervisor's recorder spends per sample it records (docs/benchmarks.md, "Receive
// path and recorder"): N agents on a degree-4 torus send their 10 Hz records, each round
// one sample per agent, 0.1 s of swarm time apart, with the recorder's periodic work (departures,
// a graph snapshot every 0.1 s) after each round, into a real run directory (telemetry.csv,
// records.pb, run.mcap). Time per item is per sample recorded, the snapshots included.
#include <benchmark/benchmark.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "common/record/recorder.hpp"
#include "common/scenario/scenario.hpp"

namespace qswarm {
namespace {

RunConfig torus(int n) {
  const int s = std::max(2, static_cast<int>(std::lround(std::sqrt(n))));
  std::string text = "name: \"torus\"\nrandom_agents { count: " + std::to_string(n) +
                     " box_m: 30 }\nmode: PARTICLE\nlaw: EDGE_FLOW\nweight { policy: UNWEIGHTED }\n"
                     "duration_s: 1000\nseed: 1\ntopology { policy: FIXED";
  for (int i = 1; i <= n; ++i)
    text += " edges { a: " + std::to_string(i) + " b: " + std::to_string(i % n + 1) +
            " } edges { a: " + std::to_string(i) + " b: " + std::to_string((i + s - 1) % n + 1) +
            " }";
  return resolve_scenario(parse_scenario_text(text + " }\n", "torus"));
}

void BM_RecorderRecords(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const RunConfig rc = torus(n);
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("qswarm-recorder-bench-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  {
    Recorder rec(rc, RunDir::claim(dir.string(), "torus", "bench"), 1.0);
    std::vector<StateMessage> m(static_cast<std::size_t>(n));
    for (std::size_t k = 0; k < m.size(); ++k) {
      const AgentSpec& a = rc.agents[k];
      m[k].view.id = a.id;
      m[k].view.q = m[k].view.q0 = a.q0();
      m[k].p_W = a.position_W;
      m[k].phase = Phase::kRunning;
      m[k].incarnation = 1;
      m[k].run_id = rc.transport.run_id;
      for (const auto& [i, j] : rc.agent.law.topology.edges)
        if (i == a.id || j == a.id) m[k].links.emplace_back(i == a.id ? j : i, 1.0);
      m[k].initial_links = m[k].links;
    }
    std::uint64_t round = 0;
    std::int64_t wall = 1'700'000'000'000'000'000;
    for (auto _ : state) {
      ++round;
      wall += 100'000'000;
      for (StateMessage& s : m) {
        s.seq = 5 * round;
        s.view.seq = round;
        s.stamp_s = 0.1 * static_cast<double>(round);
        s.wall_ns = wall;
        s.view.q *= 0.999;  // moving toward agreement: a new state each round
        rec.on_sample(s, wall + 2'000'000);
      }
      rec.tick(wall + 2'000'000);
    }
    (void)rec.finish("duration", 1.0);
  }
  std::filesystem::remove_all(dir);
  state.SetItemsProcessed(state.iterations() * n);
}
BENCHMARK(BM_RecorderRecords)->Arg(32)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace qswarm

BENCHMARK_MAIN();
