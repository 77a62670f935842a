#pragma once

#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "common/scenario/run_config.hpp"
#include "common/transport/interest.hpp"

namespace qswarm {

// Which agents an agent must hear, as partitions of the run's state stream: those that can be its
// neighbours soon, and no others, so that the traffic each process handles follows its degree, not
// the swarm's size.
//
// Space is cut into cubic cells half as wide as the link reach (threshold + hysteresis) plus twice
// a margin; an agent publishes into its cell and listens to the 5 x 5 x 5 cells about it (kSpan).
// It keeps its cell until it is half a margin outside it (moving cells makes DDS re-match its
// endpoints with every peer: an agent resting on a cell's border must not flap). The cells are in
// the space the topology measures: consensus states for proximity, physical positions for radio
// range; and, with collision avoidance, physical cells of the filter's reach too (a radio hears
// everyone near, whatever the graph). Every agent also publishes into a partition of its own id,
// which others listen to when they must hear it by name: listed edges (a FIXED graph hears only
// those), and, under sticky proximity, the links it holds (kept however far). Under `transport {
// delivery: ALL }` everyone hears everyone (the empty interest).
//
// Under `delivery: REACH` (experimental) the cells only bound who is matched with whom: of the
// samples its cells bring, an agent takes only those of senders within the reach plus a margin of
// a box about itself (Reach, judged on arrival), or that name it in a link or an exchange, and it
// moves the box once half a margin outside it (a move travels to its peers through discovery). It
// also listens to an inbox of its own, into which a peer that still settles an exchange with it
// pushes its samples. Pure.
class Neighbourhood {
 public:
  Neighbourhood(const RunConfig& rc, AgentId self);

  // The peers whose exchange with this agent is still settling (UpdateLaw::settling), and
  // whether it hears them now.
  using Settling = std::map<AgentId, bool>;

  // The interest of the agent at physical position p_W with consensus state q, holding links to
  // `linked`; it moves to another cell only once half a margin outside its own. Under REACH it
  // listens to its inbox, and pushes its samples into the inbox of a peer it still settles an
  // exchange with once it no longer hears that peer, or the exchange is still open three ticks
  // after the link ended, until it is settled: the two may no longer share a cell (particles can
  // move metres in a tick), the peer may not even know of the exchange (the one sample that told
  // it was lost), and an edge-flow exchange left unsettled would move the swarm's total.
  Interest update(const Vec3& p_W, const Vec3& q, const std::set<AgentId>& linked,
                  const Settling& settling = {});
  // Whether it hears the whole run (delivery ALL).
  bool whole_run() const { return whole_run_; }

  // The agents that agent `id` of `rc` hears at the start (at their start positions, before any
  // link): its start barrier waits for exactly these.
  static std::set<AgentId> heard_at_start(const RunConfig& rc, AgentId id);
  // Every agent's interest at its start position, before any link, in the order of rc.agents:
  // with Interest::hears, who hears whom at the start (heard_at_start; a run's predicted load).
  static std::vector<Interest> interests_at_start(const RunConfig& rc);

  // The margin beyond the link reach a cell leaves for links about to form.
  static double margin_m(double reach_m);
  // How many cells on each side of its own an agent listens to.
  static constexpr int kSpan = 2;

 private:
  struct Space {
    char tag;                             // 'q' consensus states, 'p' physical positions
    double cell_m;                        // edge of a cell
    double keep_m;                        // how far outside its cell (or its box) an agent keeps it
    double radius_m;                      // the link reach plus the margin: what it hears
    std::optional<Eigen::Vector3i> cell;  // the agent's cell, once placed
    std::optional<Vec3> anchor;  // the centre of its box (keep_m on each side), once placed
    // The names of its cell and of the cells it listens to (sorted), made when it moves cells:
    // update() runs every tick, and a move is rare.
    std::string cell_name;
    std::vector<std::string> listened;
  };
  AgentId self_;
  bool whole_run_ = false;
  bool reach_ = false;  // delivery REACH: boxes about itself, and inboxes
  std::vector<Space> spaces_;
  std::set<AgentId> listed_;
  std::map<AgentId, int> settling_;  // updates each peer has been settling for
  std::set<AgentId> pushing_;        // into whose inbox it publishes, until settled
  bool by_name_ = false;             // links are heard by name too
};

// The one definition of the peers agent `id` waits for at the start (the barrier, and the law's
// first tick): the agents it hears at the start (Neighbourhood::heard_at_start: its listed
// neighbours on a FIXED graph, the agents near enough to be neighbours otherwise, everyone under
// delivery ALL), never an agent the fault plan has joining late.
std::set<AgentId> start_peers(const RunConfig& rc, AgentId id);

}  // namespace qswarm
