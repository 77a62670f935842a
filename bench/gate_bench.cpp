// What the receive path spends per sample on the checks against forgers (docs/benchmarks.md,
// "Receive path and recorder"): the sample gate with writers known (owner, interleaving window,
// jump check) against writers unknown (one writer per agent, as before), and a writer's binding
// looked up in the WriterRegistry (one lock, one hash lookup), at 8 and 512 writers.
#include <benchmark/benchmark.h>

#include <cstring>

#include <fastdds/rtps/builtin/data/WriterProxyData.h>

#include "common/dds/writer_registry.hpp"
#include "common/transport/sample_gate.hpp"

namespace qswarm {
namespace {

StateMessage sample(AgentId id, std::uint64_t seq) {
  StateMessage m;
  m.view.id = id;
  m.seq = seq;
  m.incarnation = 1;
  m.phase = Phase::kRunning;
  return m;
}

WriterId writer_of(AgentId id) {
  WriterId w;
  std::memcpy(w.bytes.data(), &id, sizeof id);
  w.bytes[15] = 2;
  return w;
}

// Eight agents' samples in turn, as an agent of an 8-agent swarm takes them.
void BM_GateAdmit(benchmark::State& state) {
  const bool writers = state.range(0) != 0;
  SampleGate gate;
  std::vector<StateMessage> m;
  std::vector<WriterId> w;
  for (AgentId id = 1; id <= 8; ++id) {
    m.push_back(sample(id, 0));
    w.push_back(writers ? writer_of(id) : WriterId{});
  }
  std::uint64_t seq = 0;
  std::int64_t now = 1'700'000'000'000'000'000;
  for (auto _ : state) {
    ++seq;
    now += 2'500'000;
    for (std::size_t k = 0; k < m.size(); ++k) {
      m[k].seq = seq;
      benchmark::DoNotOptimize(gate.admit(m[k], "", now, w[k]));
    }
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(m.size()));
}
BENCHMARK(BM_GateAdmit)->Arg(0)->Arg(1);

// A sample's writer looked up among `n` discovered writers, each bound to its agent.
void BM_WriterBinding(benchmark::State& state) {
  const auto n = static_cast<AgentId>(state.range(0));
  WriterRegistry registry;
  std::vector<WriterId> ids;
  for (AgentId id = 1; id <= n; ++id) {
    eprosima::fastrtps::rtps::WriterProxyData d(4, 4);
    eprosima::fastrtps::rtps::GUID_t guid;
    std::memcpy(guid.guidPrefix.value, &id, sizeof id);
    guid.entityId.value[3] = 2;
    d.guid(guid);
    d.topicName("qswarm/agent_state");
    d.m_qos.m_partition.push_back("qswarm-run-0000000000000001");
    d.m_qos.m_partition.push_back(("qswarm-run-0000000000000001/a" + std::to_string(id)).c_str());
    registry.on_publisher_discovery(nullptr, eprosima::fastrtps::rtps::WriterDiscoveryInfo(d));
    ids.push_back(WriterRegistry::id_of(guid));
  }
  std::size_t k = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(registry.binding(ids[k]));
    k = (k + 1) % ids.size();
  }
}
BENCHMARK(BM_WriterBinding)->Arg(8)->Arg(512);

}  // namespace
}  // namespace qswarm
