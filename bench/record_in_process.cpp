// Records a run without processes: the scenario flown by the in-process swarm (the product's agent
// loop, every agent in one process, on a manual clock) and recorded by the real supervisor loop
// into a run directory that `swarm view` and `swarm plot` read like any other. For measuring the
// live page with a large swarm on a machine that cannot run hundreds of processes at once.
// Usage: record_in_process SCENARIO OUT_DIR [MAX_SIMULATED_S]
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>

#include "common/record/run_dir.hpp"
#include "common/scenario/scenario.hpp"
#include "common/sim/in_process_swarm.hpp"

int main(int argc, char** argv) {
  using namespace qswarm;
  if (argc < 3) {
    std::fprintf(stderr, "usage: record_in_process SCENARIO OUT_DIR [MAX_SIMULATED_S]\n");
    return 2;
  }
  try {
    const RunConfig rc = load_scenario(argv[1]);
    const double max_s = argc > 3 ? std::atof(argv[3]) : rc.judge.duration_s + 10.0;
    std::filesystem::create_directories(argv[2]);
    const RunDir dir(argv[2]);
    if (!dir.write_scenario(rc.resolved)) throw std::runtime_error("cannot write the scenario");
    InProcessSwarm swarm(rc, 1.0, dir);
    const std::string reason = swarm.run_recorded(max_s);
    std::printf("%s: %zu agents, %s\n", argv[2], rc.agents.size(), reason.c_str());
    return swarm.supervisor()->exit_code();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "record_in_process: %s\n", e.what());
    return 2;
  }
}
