#pragma once

#include <optional>
#include <string>
#include <vector>

#include "common/core/agent.hpp"
#include "common/core/math.hpp"

namespace qswarm {

// Where the agents an endpoint hears by place may be: within `radius_m` of the box [lo, hi] (the
// box holds the listening agent while it keeps this reach; the radius is its link reach plus a
// margin), in the space its topology measures: 'q' consensus states, 'p' physical positions.
struct Reach {
  char space = 'p';
  Vec3 lo = Vec3::Zero();
  Vec3 hi = Vec3::Zero();
  double radius_m = 0.0;
  bool operator==(const Reach&) const = default;
  // Whether a point lies within radius_m of the box (never for a point that is not finite).
  bool contains(const Vec3& x) const;
};

// Which parts of the run's state stream an endpoint publishes into and listens to: partitions,
// named relative to the run (the transport adds the run's own prefix, so runs stay apart), and,
// finer than partitions, where the senders it hears by place may be. The empty interest is the
// whole run: one partition everybody shares.
struct Interest {
  std::vector<std::string> publish;    // sorted, unique
  std::vector<std::string> subscribe;  // sorted, unique
  // Of the samples that reach it through a cell (a partition that names no agent), the endpoint
  // takes only those whose sender lies within one of these (none: all of them). Samples that
  // reach it by an agent's name always pass. DDS applies it on the writer's side, so a sample that
  // does not pass is never sent.
  std::vector<Reach> near;
  bool operator==(const Interest&) const = default;
  // Whether a sample published with `from` shares a partition with an endpoint's `to`.
  static bool meets(const Interest& from, const Interest& to);
  // Whether an endpoint listening with `to` hears a sample published with `from` by an agent
  // whose consensus state is q and physical position p_W, and which names the listener's agent
  // among its links or its edges' entries (`bonded`): a shared agent name, or a shared cell and
  // a place within `to.near` or a bond. A bond passes whatever the place: a link must not wait
  // for discovery to carry a moved box, and an edge-flow exchange must be settled (the swarm's
  // total depends on it) even when a particle moved metres in one tick.
  static bool hears(const Interest& to, const Interest& from, const Vec3& q, const Vec3& p_W,
                    bool bonded = false);
  // The agent whose name it publishes into (its own), if any.
  std::optional<AgentId> agent() const;
};

// The names DDS carries for an interest's partition names. A cell ("p-1.0.2": a space's tag and
// three cell indices, as Neighbourhood names it) becomes fixed-width hex ("p7fffffff.80000000.
// 80000002", each index plus 2^31), so that a listener (`patterns`) can name the cells of each
// space that fill a box with a few fnmatch(3) patterns, one per run of indices that share all
// but the last hex digit on each axis ("p7fffffff.8000000[012]..."), instead of one name per
// cell: Fast DDS matches partitions with fnmatch both ways, and a reader's announcement, which the
// Discovery Server relays to every peer on its topic, then carries at most 8 names for 125 cells.
// Other names pass unchanged; cells that do not fill a box are named one by one.
std::vector<std::string> dds_partition_names(const std::vector<std::string>& names, bool patterns);

// Regions: blocks of kRegionCells cells on each axis. Through a Discovery Server each region is a
// topic of its own ("qswarm/agent_state/rp0.-1.2") whose partitions are its cells: the server
// introduces two participants only when they share a topic, so an agent discovers the agents of
// the regions its cells touch, not the whole swarm (StateBusOptions::topic_per_name).
constexpr int kRegionCells = 5;
// The region of a cell ("p-1.0.7" -> "rp-1.0.1"); nothing for a name that is no cell.
std::optional<std::string> region_of_cell(const std::string& name);
// The cells within `span` cells of a cell on each axis, itself included, in order; none for a name
// that is no cell.
std::vector<std::string> cells_about(const std::string& cell, int span);

// The partition every agent publishes into, named for its id ("a3"): others listen to it to hear
// that agent by name, and under DDS-Security its certificate's permissions let it publish state
// only there (and in partitions that name no agent), which binds its samples to its id
// (the keystore writes the permissions, common/security/keystore.hpp; names starting with 'a' are
// reserved for it).
std::string agent_partition(AgentId id);
// The agent an agent partition names ("a3" -> 3); nothing for any other name ("a03", "a3x").
std::optional<AgentId> agent_of_partition(const std::string& name);
// An agent's inbox ("in3"): where agents that hear by place listen besides their cells, and where
// a peer pushes its samples while an exchange with that agent is left to settle and the two may
// no longer share a cell. What arrives there passes like what cells bring: by place or bond.
std::string inbox_partition(AgentId id);
std::optional<AgentId> inbox_of_partition(const std::string& name);

}  // namespace qswarm
