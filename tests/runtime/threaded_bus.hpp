#pragma once

#include <mutex>

#include "common/transport/neighbor_bus.hpp"
#include "common/transport/sample_gate.hpp"

namespace qswarm::test {

// A transport whose samples arrive on another thread, as DDS's do (its listener threads): the gate
// under one lock, the listener under another, and set_listener keeps NeighborBus's promise (once it
// returns, the old listener is neither running nor called again). For concurrency tests of what
// sits on a transport, without Fast DDS.
class ThreadFedBus final : public NeighborBus {
 public:
  // Any thread.
  void feed(const StateMessage& m) {
    SampleGate::Result r;
    {
      std::lock_guard<std::mutex> lock(mu_);
      r = gate_.admit(m, check_message(m));
    }
    if (r.verdict != SampleGate::Verdict::kAccepted) return;
    std::lock_guard<std::mutex> lock(listener_mu_);
    if (listener_) listener_(m);
  }
  void publish(const StateMessage&) override {
    std::lock_guard<std::mutex> lock(mu_);
    ++gate_.counters().published;
  }
  void record(const StateMessage&) override {}
  void for_each_latest(AgentId self,
                       const std::function<void(const StateMessage&)>& visit) override {
    std::lock_guard<std::mutex> lock(mu_);
    gate_.for_each_latest(self, visit);
  }
  void set_listener(Listener listener) override {
    std::lock_guard<std::mutex> lock(listener_mu_);
    listener_ = std::move(listener);
  }
  BusCounters counters() const override {
    std::lock_guard<std::mutex> lock(mu_);
    return gate_.counters();
  }

 private:
  mutable std::mutex mu_;
  SampleGate gate_;
  std::mutex listener_mu_;
  Listener listener_;
};

}  // namespace qswarm::test
