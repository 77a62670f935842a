#include "common/transport/in_memory_bus.hpp"

#include <algorithm>

namespace qswarm {

void InMemoryNetwork::attach(InMemoryBus* bus) { endpoints_.push_back(bus); }

void InMemoryNetwork::detach(InMemoryBus* bus) {
  endpoints_.erase(std::remove(endpoints_.begin(), endpoints_.end(), bus), endpoints_.end());
  for (auto& [from, m] : queue_)
    if (from == bus) from = nullptr;
}

void InMemoryNetwork::post(const InMemoryBus* from, const StateMessage& m) {
  queue_.emplace_back(from, m);
}

void InMemoryNetwork::deliver() {
  std::vector<std::pair<const InMemoryBus*, StateMessage>> round;
  round.swap(queue_);
  for (const auto& [from, m] : round) {
    for (InMemoryBus* to : endpoints_)
      if (to != from) to->receive(m);
  }
}

InMemoryBus::InMemoryBus(InMemoryNetwork& net) : net_(net) { net_.attach(this); }

InMemoryBus::~InMemoryBus() { net_.detach(this); }

void InMemoryBus::publish(const StateMessage& msg) {
  ++gate_.counters().published;
  net_.post(this, msg);
}

void InMemoryBus::receive(const StateMessage& m) {
  if (gate_.admit(m, check_message(m)).verdict == SampleGate::Verdict::kAccepted && listener_) {
    listener_(m);
  }
}

}  // namespace qswarm
