#include "common/runtime/faulty_bus.hpp"

namespace qswarm {

FaultyBus::FaultyBus(NeighborBus& inner, LinkFaults faults, AgentId self)
    : inner_(inner), faults_(std::move(faults)), self_(self), direct_(faults_.none()) {
  inner_.set_listener([this](const StateMessage& m) { deliver(m); });
}

FaultyBus::~FaultyBus() { inner_.set_listener(nullptr); }

void FaultyBus::set_time(double t) {
  std::vector<StateMessage> released;
  {
    std::lock_guard<std::mutex> lock(mu_);
    t_s_ = t;
    release_due_locked(has_listener_ ? &released : nullptr);  // nothing to collect without one
  }
  notify(released);
}

void FaultyBus::set_listener(Listener listener) {
  std::lock_guard<std::mutex> lock(listener_mu_);
  has_listener_ = static_cast<bool>(listener);
  listener_ = std::move(listener);
}

void FaultyBus::notify(const std::vector<StateMessage>& released) {
  if (released.empty()) return;
  // Held while the listener runs, so that set_listener keeps NeighborBus's promise.
  std::lock_guard<std::mutex> lock(listener_mu_);
  if (listener_)
    for (const StateMessage& m : released) listener_(m);
}

void FaultyBus::deliver(const StateMessage& m) {
  if (direct_) {
    if (m.view.id == self_ || !has_listener_) return;
    std::lock_guard<std::mutex> lock(listener_mu_);
    if (listener_) listener_(m);
    return;
  }
  std::vector<StateMessage> released;
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (m.view.id == self_) return;
    const LinkFaults::Verdict v = faults_.on_receive(m.view.id, t_s_);
    if (v.drop) return;
    held_.emplace(t_s_ + v.delay_s, Arrival{++arrivals_, m});
    release_due_locked(has_listener_ ? &released : nullptr);  // nothing to collect without one
  }
  notify(released);
}

void FaultyBus::release_due_locked(std::vector<StateMessage>* released) {
  while (!held_.empty() && held_.begin()->first <= t_s_) {
    const Arrival& a = held_.begin()->second;
    auto it = latest_.find(a.m.view.id);
    // Jitter can reorder: keep the one the transport accepted last.
    if (it == latest_.end() || a.index > it->second.index) {
      latest_[a.m.view.id] = a;
      if (released) released->push_back(a.m);
    }
    held_.erase(held_.begin());
  }
}

void FaultyBus::for_each_latest(AgentId self,
                                const std::function<void(const StateMessage&)>& visit) {
  if (direct_) return inner_.for_each_latest(self, visit);
  std::lock_guard<std::mutex> lock(mu_);
  release_due_locked(nullptr);
  for (const auto& [id, a] : latest_)
    if (id != self) visit(a.m);
}

FaultCounters FaultyBus::fault_counters() const {
  std::lock_guard<std::mutex> lock(mu_);
  return faults_.counters();
}

}  // namespace qswarm
