#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <set>
#include <vector>

#include "common/transport/interest.hpp"
#include "common/transport/state_message.hpp"

namespace qswarm {

// How old accepted samples were when they arrived: the receiver's wall clock against the one the
// sample carries, which only means something between processes of one host (one clock) and
// which a sender may forge. Bins four to an octave from 10 us: the first holds everything younger
// than 10 us, the last, open, everything from 14.8 s on. A sample stamped after it arrived (a
// clock stepped back, a forged stamp) is counted apart, in no bin.
struct ArrivalAges {
  static constexpr int kBins = 84;
  std::array<std::uint64_t, kBins> count{};
  std::uint64_t early = 0;  // stamped after it arrived
  void add(std::int64_t age_ns);
  std::uint64_t total() const;  // in the bins
  // The q-quantile (0 < q <= 1) of the binned ages in milliseconds: the upper edge of its bin,
  // at most 19 % above the true value (0.01 ms for anything in the first), infinity in the last;
  // -1 without samples.
  double quantile_ms(double q) const;
  static double upper_edge_ms(int bin);
};

struct BusCounters {
  std::uint64_t published = 0;
  std::uint64_t received = 0;  // accepted samples
  std::uint64_t dropped = 0;   // refused: invalid content
  std::uint64_t stale = 0;     // refused: not newer than what we hold
  std::uint64_t foreign = 0;   // refused: from another run on the same domain
  // refused: another writer holds the agent's key (SampleGate), or a sequence jump
  std::uint64_t contested = 0;
  ArrivalAges ages;  // of the accepted samples that carry a wall time
};

// The one narrow interface an agent uses to talk: publish its own state, read the newest state of
// every other agent it hears. DDS implements it for the product (common/dds), InMemoryBus for
// tests and the in-process swarm, FaultyBus (common/runtime) decorates either with link faults.
class NeighborBus {
 public:
  using Listener = std::function<void(const StateMessage&)>;

  virtual ~NeighborBus() = default;
  virtual void publish(const StateMessage& msg) = 0;
  // Sends a sample to the recorder (the supervisor) only, on a stream of its own: agents send it
  // every k-th sample (the record rate), so what the record costs does not grow with their rate.
  virtual void record(const StateMessage& msg) = 0;
  // Passes the newest accepted message of every agent other than `self` (one per agent, in id
  // order) to `visit`, without copying it: an agent reads its neighbours so at every tick.
  // `visit` runs under the bus's lock and must not call the bus.
  virtual void for_each_latest(AgentId self,
                               const std::function<void(const StateMessage&)>& visit) = 0;
  // The same messages, copied.
  std::vector<StateMessage> latest(AgentId self) {
    std::vector<StateMessage> out;
    for_each_latest(self, [&](const StateMessage& m) { out.push_back(m); });
    return out;
  }
  // Called for every accepted sample, possibly on a transport thread. When set_listener returns,
  // the previous listener is not running and is never called again: a decorator that registers
  // itself can unregister in its destructor and be destroyed safely while samples still flow.
  virtual void set_listener(Listener listener) = 0;
  // What the transport accepted and refused (SampleGate).
  virtual BusCounters counters() const = 0;
  // Readers matched to our writer (DDS discovery: the start barrier waits for the supervisor's).
  virtual int matched_readers() const { return 0; }
  // Whether a recorder hears our record stream: one matched it and acknowledged what we recorded
  // since (the start barrier waits for it, so that the record holds every agent from the start).
  // A writer's match alone does not say it: the recorder may not yet know our writer, and drops
  // what it sends until it does.
  virtual bool recorder_confirmed() const { return false; }
  // Which parts of the state stream this endpoint publishes into and hears (the agents that can
  // be its neighbours: see Neighbourhood). The default is the whole run.
  virtual void set_interest(const Interest& interest) { (void)interest; }
  // Other runs heard on this transport (their run ids; their samples were refused as foreign).
  virtual std::set<std::uint64_t> foreign_runs() const { return {}; }
  // Ids outside the run whose samples the transport dropped before the gate saw them (the DDS
  // roster filter), so that the record can still name each stranger once.
  virtual std::set<AgentId> strangers() const { return {}; }
  // Agents whose samples this transport found forged, with SuspectKind bits (SampleGate).
  virtual std::map<AgentId, std::uint8_t> suspects() const { return {}; }
};

}  // namespace qswarm
