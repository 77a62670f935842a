#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <vector>

#include "common/core/topology.hpp"
#include "common/transport/state_message.hpp"

namespace qswarm {

// Who of the run's agents is here, judged in simulated time like the agents judge their
// neighbours: an agent whose samples stop for longer than the neighbour timeout (on the swarm's
// clock) has departed; a Phase::kStopping sample is a departure at once; a sample after a departure
// is a rejoin. Strangers (ids not in the run) are kept apart. Pure: it is told the time.
class Presence {
 public:
  struct Track {
    StateMessage first, last;
    bool seen = false;
    bool present = false;
    bool ran = false;  // it left its start barrier: a sample of it running or of its law ticking
    double last_heard_s = 0.0;  // swarm time when its newest sample arrived
    std::uint64_t samples = 0, gaps = 0;
  };
  enum class Change { kNone, kJoin, kRejoin, kDepart, kStranger, kStrangerAgain };

  // `record_every`: agents send every k-th of their samples (RunConfig::record_every), so a gap in
  // sequence numbers of k is no loss.
  Presence(const std::vector<AgentId>& ids, double timeout_s, std::uint32_t record_every = 1);
  // A sample arrived at swarm time now_s. Returns what changed for its agent.
  Change on_sample(const StateMessage& m, double now_s);
  // Agents silent past the timeout at swarm time now_s: marked departed and returned.
  std::vector<AgentId> expire(double now_s);

  const std::map<AgentId, Track>& tracks() const { return tracks_; }
  const Track& track(AgentId id) const { return tracks_.at(id); }
  bool running(AgentId id) const;
  std::size_t present_count() const;
  std::size_t seen_count() const;
  std::size_t strangers() const { return strangers_.size(); }
  // A stranger known without a sample (the DDS roster filter dropped its samples): true the first
  // time its id is told.
  // At most kMaxStrangers are kept (reports of strangers come from the network).
  bool note_stranger(AgentId id) {
    return tracks_.count(id) == 0 && strangers_.size() < kMaxStrangers &&
           strangers_.insert(id).second;
  }
  static constexpr std::size_t kMaxStrangers = 1024;

 private:
  std::map<AgentId, Track> tracks_;
  std::set<AgentId> strangers_;
  double timeout_s_;
  std::uint32_t every_;
};

}  // namespace qswarm
