#pragma once

#include <cstddef>

#include "common/scenario/run_config.hpp"
#include "common/scenario/run_plan.hpp"

namespace qswarm::test {

// The plan of a swarm of `n` agents (ids 1..n, every other setting the default) on these hosts:
// what the size alone decides, as the run plan's table test and the layers' tests read it.
inline RunPlan plan_for(std::size_t n, bool secure = false, Hosts hosts = {}) {
  RunConfig rc;
  for (std::size_t i = 0; i < n; ++i) {
    AgentSpec a;
    a.id = static_cast<AgentId>(i + 1);
    rc.agents.push_back(a);
  }
  if (secure) rc.transport.keystore = "/keys";
  rc.transport.run_id = 1;
  return plan_run(rc, hosts);
}

}  // namespace qswarm::test
