#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "common/claim/id_claim.hpp"

namespace qswarm {

// How replicas that were started identically (compose's `deploy.replicas`, which gives a container
// no index) come to fly distinct agent ids, with no coordinator and no per-replica setting.
//
// Every replica draws a random 64-bit nonce and announces {nonce, expected N, id, stage} a few
// times a second. A replica without an id waits until it hears exactly N live replicas (itself
// included), has heard every claim writer DDS matched, and that set has not changed for
// `settle_s`; then the ids nobody holds yet are handed out by the rank of the nonces of the
// replicas that hold none: every replica with the same view computes the same assignment, so
// nobody waits for anybody's answer. A replica given an id (--id K) announces it from the start
// (auto replicas count it as held) and also waits for all N before confirming it. Before
// flying, a replica announces its id for `confirm_s` (confirming) without publishing any state.
// The rules that keep one id from being flown twice:
//   - an id confirmed or flown by another replica is not taken: a replica given it refuses, a
//     ranking replica counts it as held;
//   - two replicas confirming one id: the larger nonce backs off (given the id: refuses; auto:
//     ranks again), before either flies;
//   - a flying replica never yields to a newcomer; two flying one id (a healed network split, a
//     discovery later than settle + confirm): the later flight yields and stops;
//   - a replica ranked past the free ids (more replicas than agents) refuses;
//   - replicas told different N refuse while they choose (the swarm's size is one setting, not
//     two); a flying replica ignores a stray one.
// A replica that died stays live for expire_s: a replacement started within that time can find
// the view crowded (known limit; the claim timeout then says so).
// Pure: the caller feeds the claims heard and the time; tests drive it with numbers.
class IdClaimer {
 public:
  struct Config {
    double period_s = 0.1;     // announce this often
    double settle_s = 1.0;     // the set of live replicas must hold still this long
    double expire_s = 2.0;     // a replica unheard this long is gone
    double confirm_s = 1.0;    // announce the id this long before flying it
    double timeout_s = 120.0;  // give up waiting for N replicas after this long

    // Claims every `period_s` (the run plan's: every replica announces to every other, n^2 claims
    // per period, so a larger swarm claims less often), the windows that depend on it widened to
    // match, and a claim given up after `timeout_s`.
    static Config with_period(double period_s, double timeout_s);
  };
  // `roster`: the run's agent ids (sorted); `fixed`: an id given by hand, 0 for none.
  IdClaimer(std::vector<AgentId> roster, std::uint64_t nonce, std::uint64_t run_id, AgentId fixed,
            Config cfg, double now_s);

  struct Step {
    bool announce = false;  // publish `claim()` now
    AgentId taken = 0;      // set once, when the id is confirmed: fly it
    bool refuse = false;    // stop: `message` says why
    std::string message;
  };
  // `heard`: the latest claim of every replica heard (its own may be among them: ignored);
  // `matched_writers`: claim writers DDS matched to this replica's reader, its own included (-1:
  // unknown, as in tests without DDS).
  Step step(double now_s, const std::vector<IdClaim>& heard, int matched_writers = -1);

  // Where the claim stands, for a progress line: replicas heard of N, how long the view has held
  // still (of settle_s), how many times it changed, the matched claim writers.
  std::string status(double now_s, int matched_writers) const;

  const IdClaim& claim() const { return mine_; }
  AgentId id() const { return mine_.id; }
  // Live replicas heard, itself included.
  std::size_t live() const { return live_.size() + 1; }
  // Other replicas it remembers: the live ones and those the bus still reports (bounded by the
  // bus, not by how many replicas ever came and went).
  std::size_t remembered() const { return seen_.size(); }

 private:
  struct Seen {
    std::uint64_t seq = 0;
    double heard_s = 0.0;
    IdClaim claim;
  };
  std::vector<AgentId> roster_;
  Config cfg_;
  IdClaim mine_;
  AgentId fixed_ = 0;
  double start_s_ = 0.0;
  double confirm_since_s_ = 0.0;
  double flying_since_s_ = 0.0;
  double next_announce_s_ = 0.0;
  std::map<std::uint64_t, Seen> seen_;     // the nonces the bus reports, and live ones
  std::map<std::uint64_t, IdClaim> live_;  // heard within expire_s, without mine
  std::vector<std::uint64_t> view_;        // the live nonces at the last change
  double view_since_s_ = 0.0;
  std::uint64_t view_changes_ = 0;
  std::uint64_t expiries_ = 0;  // replicas dropped for silence (and heard again, if they flap)
};

}  // namespace qswarm
