#pragma once

#include <functional>
#include <map>
#include <vector>

#include "common/transport/neighbor_bus.hpp"
#include "common/transport/sample_gate.hpp"

namespace qswarm {

class InMemoryBus;
enum class InMemoryRole { kAgent, kRecorder };

// Agents in one process, in lockstep: what endpoints publish during a round is delivered to every
// other endpoint at deliver(), so every agent reads the others' messages of the previous round
// whatever order the agents ran in. Samples go to agents' endpoints, records to recorders'.
// Deterministic; single-threaded.
class InMemoryNetwork {
 public:
  void attach(InMemoryBus* bus);
  void detach(InMemoryBus* bus);
  void post(const InMemoryBus* from, const StateMessage& m, bool record = false);
  // Hands every posted message to every other attached endpoint of its stream, in posting order.
  void deliver();
  int endpoints(InMemoryRole role) const;
  // What `from` sends is rewritten for each endpoint `to` before it arrives (samples and records
  // alike): how a test puts an insider that lies on the network, to every listener alike or to
  // each its own.
  using Rewrite =
      std::function<void(const InMemoryBus& from, const InMemoryBus& to, StateMessage& m)>;
  void set_rewrite(Rewrite rewrite) { rewrite_ = std::move(rewrite); }

 private:
  struct Posted {
    const InMemoryBus* from;
    StateMessage m;
    bool record;
    Interest published;  // where the sender published it
  };
  std::vector<InMemoryBus*> endpoints_;
  std::vector<Posted> queue_;
  Rewrite rewrite_;
};

// One agent's endpoint on an InMemoryNetwork: it admits samples through the same SampleGate as
// the DDS bus (checks, staleness, counters).
class InMemoryBus final : public NeighborBus {
 public:
  using Role = InMemoryRole;
  // An agent's endpoint hears samples; a recorder's (the supervisor's) hears records. `law`: the
  // run's law, whose samples alone the gate admits (as the DDS bus's gate does).
  explicit InMemoryBus(InMemoryNetwork& net, Role role = Role::kAgent, ExpectedLaw law = {});
  ~InMemoryBus() override;
  InMemoryBus(const InMemoryBus&) = delete;
  InMemoryBus& operator=(const InMemoryBus&) = delete;

  void publish(const StateMessage& msg) override;
  void record(const StateMessage& msg) override { net_.post(this, msg, true); }
  bool recorder_confirmed() const override { return net_.endpoints(Role::kRecorder) > 0; }
  // Every other agent's endpoint hears what this one publishes.
  int matched_readers() const override {
    return net_.endpoints(Role::kAgent) - (role_ == Role::kAgent ? 1 : 0);
  }
  Role role() const { return role_; }
  void set_interest(const Interest& interest) override { interest_ = interest; }
  const Interest& interest() const { return interest_; }
  void for_each_latest(AgentId self,
                       const std::function<void(const StateMessage&)>& visit) override {
    gate_.for_each_latest(self, visit);
  }
  void set_listener(Listener listener) override { listener_ = std::move(listener); }
  // A sample arriving from the network (or a test acting as a stranger on it).
  void receive(const StateMessage& m);
  BusCounters counters() const override { return gate_.counters(); }
  std::set<std::uint64_t> foreign_runs() const override { return gate_.foreign_runs(); }

 private:
  InMemoryNetwork& net_;
  Role role_;
  Interest interest_;
  SampleGate gate_;
  Listener listener_;
};

}  // namespace qswarm
