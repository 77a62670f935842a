#include "common/transport/in_memory_bus.hpp"

#include <algorithm>
#include <optional>

namespace qswarm {

void InMemoryNetwork::attach(InMemoryBus* bus) { endpoints_.push_back(bus); }

void InMemoryNetwork::detach(InMemoryBus* bus) {
  endpoints_.erase(std::remove(endpoints_.begin(), endpoints_.end(), bus), endpoints_.end());
  for (Posted& p : queue_)
    if (p.from == bus) p.from = nullptr;
}

void InMemoryNetwork::post(const InMemoryBus* from, const StateMessage& m, bool record) {
  queue_.push_back({from, m, record, from ? from->interest() : Interest{}});
}

void InMemoryNetwork::deliver() {
  std::vector<Posted> round;
  round.swap(queue_);
  for (const Posted& p : round) {
    const InMemoryBus::Role to_role =
        p.record ? InMemoryBus::Role::kRecorder : InMemoryBus::Role::kAgent;
    for (InMemoryBus* to : endpoints_) {
      if (to == p.from || to->role() != to_role) continue;
      // A record goes to every recorder; a sample to whoever listens where it was published.
      if (!p.record) {
        const std::optional<AgentId> listener = to->interest().agent();
        if (!Interest::hears(to->interest(), p.published, p.m.view.q, p.m.p_W,
                             listener && mentions(p.m, *listener)))
          continue;
      }
      if (rewrite_ && p.from) {
        StateMessage m = p.m;
        rewrite_(*p.from, *to, m);
        to->receive(m);
      } else {
        to->receive(p.m);
      }
    }
  }
}

int InMemoryNetwork::endpoints(InMemoryRole role) const {
  return static_cast<int>(
      std::count_if(endpoints_.begin(), endpoints_.end(),
                    [role](const InMemoryBus* b) { return b->role() == role; }));
}

InMemoryBus::InMemoryBus(InMemoryNetwork& net, Role role, ExpectedLaw law)
    : net_(net), role_(role), gate_(0, law) {
  net_.attach(this);
}

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
