#pragma once

// Inside the DDS adapter: how the state stream reaches who hears it, one routing each
// (transport/routing.hpp). A route makes, moves and deletes its endpoints as the interest changes;
// the bus (state_bus.cpp) admits what they read.

#include <memory>
#include <optional>
#include <string>

#include "common/dds/state_endpoints.hpp"

namespace qswarm_msgs {
class AgentState;
}

namespace qswarm::state_bus {

class StateRoute {
 public:
  virtual ~StateRoute() = default;
  // Where the agent publishes and listens now: endpoints made, moved or deleted.
  virtual void set_interest(const Interest& interest) = 0;
  // Writes the sample on each of its writers that readers matched: false if a write failed,
  // nothing if it has no writer.
  virtual std::optional<bool> write(qswarm_msgs::AgentState& sample) = 0;
  // Readers matched to the writers it writes.
  virtual int matched_readers() const = 0;
  // The readers matched with its writer on a region's topic (region routing only).
  virtual int region_readers_matched(const std::string& region) const;
};

// route_partitions.cpp: one writer and one reader of the shared topic; the interest's names are
// their partitions, the writer always also in its agent's (which binds it to its agent).
std::unique_ptr<StateRoute> partitions_route(StateEndpoints& e);
// route_named.cpp: agent names and inboxes are topics of their own; cells are partitions of the
// shared topic, or with `regions` of their region's topic (route_regions.cpp).
std::unique_ptr<StateRoute> named_route(StateEndpoints& e, bool regions);

// route_regions.cpp: cells as partitions of their region's topic. A reader per region the
// listened cells touch, in the subscriber the route hands it (whose partitions are those cells).
// A writer per region the published cell lies in (active: written), and one per other region
// within a cell of it (idle: matched with the readers of those cells, never written), so that a
// move into another region finds a writer its new readers already matched: a new writer would be
// heard only once the Discovery Server had relayed it.
class RegionEndpoints {
 public:
  RegionEndpoints(StateEndpoints& e, dds::Subscriber* sub) : e_(e), sub_(sub) {}
  ~RegionEndpoints();
  RegionEndpoints(const RegionEndpoints&) = delete;
  RegionEndpoints& operator=(const RegionEndpoints&) = delete;
  // Deletes the readers of regions none of these listened cells lies in. They share the
  // subscriber with the shared topic's reader, and go before its partitions change: a reader
  // updated and then deleted at once would reach a Discovery Server as two changes together.
  void drop_readers_beyond(const std::vector<std::string>& cells);
  // The region endpoints for these published and listened cells (after drop_readers_beyond).
  void set(const std::vector<std::string>& pub, const std::vector<std::string>& sub);
  bool write(qswarm_msgs::AgentState& sample);
  bool writers() const { return !writers_.empty(); }
  int matched_readers() const;
  int readers_matched(const std::string& region) const;

 private:
  struct RegionWriter {
    Writer w;
    bool active = false;
  };
  void drop(const std::string& region, bool its_reader, bool its_writer);
  StateEndpoints& e_;
  dds::Subscriber* sub_;
  std::map<std::string, RegionWriter> writers_;
  std::map<std::string, Reader> readers_;
};

}  // namespace qswarm::state_bus
