#pragma once

#include <atomic>
#include <map>
#include <mutex>

#include "common/runtime/link_faults.hpp"
#include "common/transport/neighbor_bus.hpp"

namespace qswarm {

// The fault-injecting decorator of a NeighborBus: it registers itself as the inner bus's listener,
// passes every sample through LinkFaults (drop, or hold until a delay elapses) and serves the
// newest samples (for_each_latest) from what survived. Publishing goes straight to the inner bus.
// With no link faults planned it stands aside: samples go straight to its listener and
// for_each_latest is the inner bus's (the same newest accepted sample per agent), so an agent pays
// no copy and no lock per sample for faults nobody planned. Thread-safe: samples may arrive on a
// transport thread. The destructor unregisters first, so no sample reaches a destroyed bus.
class FaultyBus final : public NeighborBus {
 public:
  FaultyBus(NeighborBus& inner, LinkFaults faults, AgentId self);
  ~FaultyBus() override;
  FaultyBus(const FaultyBus&) = delete;
  FaultyBus& operator=(const FaultyBus&) = delete;

  // The simulated time that fault windows and delays are judged at.
  void set_time(double t_s);
  void publish(const StateMessage& msg) override { inner_.publish(msg); }
  void record(const StateMessage& msg) override { inner_.record(msg); }
  bool recorder_confirmed() const override { return inner_.recorder_confirmed(); }
  void set_interest(const Interest& interest) override { inner_.set_interest(interest); }
  void for_each_latest(AgentId self,
                       const std::function<void(const StateMessage&)>& visit) override;
  void set_listener(Listener listener) override;
  BusCounters counters() const override { return inner_.counters(); }
  int matched_readers() const override { return inner_.matched_readers(); }
  FaultCounters fault_counters() const;

 private:
  void deliver(const StateMessage& m);
  void release_due_locked(std::vector<StateMessage>* released);
  void notify(const std::vector<StateMessage>& released);
  NeighborBus& inner_;
  LinkFaults faults_;
  AgentId self_;
  bool direct_ = false;  // no link faults planned: pass samples through
  mutable std::mutex mu_;
  double t_s_ = 0.0;
  // A sample the transport accepted, in the order it did: the transport (SampleGate) judges which
  // sample of an agent is newest, including a takeover by another writer that numbers its samples
  // lower (a restart, or the real agent after a forger stopped); delays here only reorder.
  struct Arrival {
    std::uint64_t index = 0;
    StateMessage m;
  };
  std::uint64_t arrivals_ = 0;
  std::multimap<double, Arrival> held_;  // release time -> sample
  std::map<AgentId, Arrival> latest_;
  std::mutex listener_mu_;  // held while listener_ runs or is replaced
  std::atomic<bool> has_listener_{false};
  Listener listener_;
};

}  // namespace qswarm
