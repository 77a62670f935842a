#pragma once

#include <map>
#include <vector>

#include "common/transport/state_message.hpp"

namespace qswarm {

// The one narrow interface an agent uses to talk: publish its own state, read the newest state of
// every other agent it hears. DDS implements it for the product; InMemoryBus for tests.
class NeighborBus {
 public:
  virtual ~NeighborBus() = default;
  virtual void publish(const StateMessage& msg) = 0;
  // Newest message of every agent other than `self` (one per agent).
  virtual std::vector<StateMessage> latest(AgentId self) = 0;
};

// All agents in one process share one table of newest messages.
class InMemoryBus final : public NeighborBus {
 public:
  void publish(const StateMessage& msg) override { latest_[msg.view.id] = msg; }
  std::vector<StateMessage> latest(AgentId self) override {
    std::vector<StateMessage> out;
    out.reserve(latest_.size());
    for (const auto& [id, m] : latest_)
      if (id != self) out.push_back(m);
    return out;
  }

 private:
  std::map<AgentId, StateMessage> latest_;
};

}  // namespace qswarm
