#pragma once

#include <cstdint>

#include "common/dds/dds_bus.hpp"
#include "common/transport/state_message.hpp"
#include "tests/swarm/domain_lease.hpp"

namespace qswarm::test {

// A participant of run `run` on this test's leased domain. A recorder reads the record stream of
// every run (as the supervisor does) and publishes nothing.
inline DdsOptions dds_options(const char* name, std::uint64_t run, bool recorder = false) {
  DdsOptions o;
  o.participant.domain_id = static_cast<std::uint32_t>(test_domain().domain());
  o.participant.name = name;
  o.state.max_agents = 16;
  o.state.run_id = run;
  o.state.recorder = recorder;
  o.state.publish = !recorder;
  o.state.hear_all_runs = recorder;
  return o;
}

// A well-formed state sample of agent `id` in run `run`: what the DDS tests publish.
inline StateMessage state_sample(AgentId id, std::uint64_t run, std::uint64_t seq,
                                 Phase phase = Phase::kRunning) {
  StateMessage m;
  m.view.id = id;
  m.seq = seq;
  m.run_id = run;
  m.phase = phase;
  return m;
}

}  // namespace qswarm::test
