#pragma once

#include <map>
#include <vector>

#include "common/transport/neighbor_bus.hpp"
#include "common/transport/sample_gate.hpp"

namespace qswarm {

class InMemoryBus;

// Agents in one process, in lockstep: what endpoints publish during a round is delivered to every
// other endpoint at deliver(), so every agent reads the others' messages of the previous round
// whatever order the agents ran in. Deterministic; single-threaded.
class InMemoryNetwork {
 public:
  void attach(InMemoryBus* bus);
  void detach(InMemoryBus* bus);
  void post(const InMemoryBus* from, const StateMessage& m);
  // Hands every posted message to every other attached endpoint, in posting order.
  void deliver();

 private:
  std::vector<InMemoryBus*> endpoints_;
  std::vector<std::pair<const InMemoryBus*, StateMessage>> queue_;
};

// One agent's endpoint on an InMemoryNetwork: it admits samples through the same SampleGate as
// the DDS bus (checks, staleness, counters).
class InMemoryBus final : public NeighborBus {
 public:
  explicit InMemoryBus(InMemoryNetwork& net);
  ~InMemoryBus() override;
  InMemoryBus(const InMemoryBus&) = delete;
  InMemoryBus& operator=(const InMemoryBus&) = delete;

  void publish(const StateMessage& msg) override;
  std::vector<StateMessage> latest(AgentId self) override { return gate_.latest(self); }
  void set_listener(Listener listener) override { listener_ = std::move(listener); }
  // A sample arriving from the network (or a test acting as a stranger on it).
  void receive(const StateMessage& m);
  BusCounters counters() const override { return gate_.counters(); }
  std::set<std::uint64_t> foreign_runs() const override { return gate_.foreign_runs(); }

 private:
  InMemoryNetwork& net_;
  SampleGate gate_;
  Listener listener_;
};

}  // namespace qswarm
