#include "common/claim/id_claimer.hpp"

#include <algorithm>
#include <cstdio>
#include <set>

namespace qswarm {

namespace {
std::string hex(std::uint64_t v) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}
}  // namespace

IdClaimer::Config IdClaimer::Config::with_period(double period_s, double timeout_s) {
  Config c;
  c.timeout_s = timeout_s;
  c.period_s = period_s;
  // A replica is gone after 15 silent periods (8 s at 32): on saturated cores a live replica's
  // claims can go unheard for seconds, and each such gap changes every view and restarts the
  // settle wait, so a shorter expiry keeps a large swarm from ever settling (docs/architecture.md,
  // "The compose swarm").
  c.expire_s = std::max(c.expire_s, 15.0 * c.period_s);
  c.settle_s = std::max(c.settle_s, 3.0 * c.period_s);
  c.confirm_s = std::max(c.confirm_s, 3.0 * c.period_s);
  return c;
}

IdClaimer::IdClaimer(std::vector<AgentId> roster, std::uint64_t nonce, std::uint64_t run_id,
                     AgentId fixed, Config cfg, double now_s)
    : roster_(std::move(roster)), cfg_(cfg), start_s_(now_s), view_since_s_(now_s) {
  std::sort(roster_.begin(), roster_.end());
  mine_.nonce = nonce;
  mine_.run_id = run_id;
  mine_.expected = static_cast<std::uint32_t>(roster_.size());
  fixed_ = fixed;
  mine_.id = fixed;  // a given id is announced from the start: auto replicas leave it alone
  view_ = {nonce};
}

std::string IdClaimer::status(double now_s, int matched_writers) const {
  char buf[200];
  std::snprintf(buf, sizeof buf,
                "claiming: heard %zu of %u replicas, view still for %.1f s (needs %.1f), %llu view "
                "changes, %llu silences past %.1f s, %d claim writers matched",
                live(), mine_.expected, now_s - view_since_s_, cfg_.settle_s,
                static_cast<unsigned long long>(view_changes_),
                static_cast<unsigned long long>(expiries_), cfg_.expire_s, matched_writers);
  return buf;
}

IdClaimer::Step IdClaimer::step(double now_s, const std::vector<IdClaim>& heard,
                                int matched_writers) {
  std::set<std::uint64_t> reported;
  for (const IdClaim& c : heard) {
    reported.insert(c.nonce);
    if (c.nonce == mine_.nonce) continue;
    auto [it, fresh] = seen_.try_emplace(c.nonce);
    if (fresh || it->second.seq != c.seq) it->second.heard_s = now_s;
    it->second.seq = c.seq;
    it->second.claim = c;
  }
  std::vector<std::uint64_t> view{mine_.nonce};
  std::map<std::uint64_t, IdClaim> now_live;
  for (auto it = seen_.begin(); it != seen_.end();) {
    const auto& [nonce, s] = *it;
    if (now_s - s.heard_s > cfg_.expire_s) {
      if (live_.count(nonce)) ++expiries_;
      // Forgotten once the bus no longer reports it either: a nonce heard again after that comes
      // with a new claim, so it is alive. seen_ stays as large as the bus's bounded map.
      it = reported.count(nonce) ? std::next(it) : seen_.erase(it);
      continue;
    }
    now_live[nonce] = s.claim;
    view.push_back(nonce);
    ++it;
  }
  live_.swap(now_live);
  std::sort(view.begin(), view.end());
  if (view != view_) {
    view_ = view;
    view_since_s_ = now_s;
    ++view_changes_;
  }
  // Ready to decide: the view held still, this replica listened long enough, and every claim
  // writer DDS matched has been heard.
  const bool ready = now_s - view_since_s_ >= cfg_.settle_s && now_s - start_s_ >= cfg_.settle_s &&
                     (matched_writers < 0 || live() >= static_cast<std::size_t>(matched_writers));

  Step s;
  if (now_s >= next_announce_s_) {
    s.announce = true;
    ++mine_.seq;
    next_announce_s_ = now_s + cfg_.period_s;
  }
  if (mine_.stage == kFlying) mine_.flying_s = now_s - flying_since_s_;
  const auto refuse = [&s](std::string why) {
    s.refuse = true;
    s.message = std::move(why);
    return s;
  };
  for (const auto& [nonce, c] : live_) {
    // Only a replica still choosing refuses over the swarm's size: a stray replica told another N
    // must not stop a swarm that flies.
    if (mine_.stage == kRanking && c.expected != mine_.expected)
      return refuse("replica " + hex(nonce) + " was told the swarm has " +
                    std::to_string(c.expected) + " agents and this one " +
                    std::to_string(mine_.expected) +
                    ": every replica needs the same swarm size (QSWARM_AGENTS)");
  }
  const auto held_by_other = [&](AgentId id) -> std::uint64_t {
    for (const auto& [nonce, c] : live_) {
      if (c.id != id || c.stage == kRanking) continue;
      if (c.stage == kFlying && mine_.stage != kFlying) return nonce;
      if (c.stage == kFlying && mine_.stage == kFlying) {
        // Two flights of one id (a healed split, a late discovery): the earlier keeps it; their
        // start times, each on this replica's clock, are compared with a margin of 0.25 s.
        const double other_since = seen_.at(nonce).heard_s - c.flying_s;
        if (other_since < flying_since_s_ - 0.25) return nonce;
        if (other_since <= flying_since_s_ + 0.25 && nonce < mine_.nonce) return nonce;
        continue;
      }
      if (c.stage == mine_.stage && nonce < mine_.nonce) return nonce;
      if (mine_.stage == kRanking) return nonce;
    }
    return 0;
  };
  const auto already_held = [&](std::uint64_t holder) {
    return refuse("agent id " + std::to_string(mine_.id != 0 ? mine_.id : fixed_) +
                  " is already held by another replica (" + hex(holder) +
                  "): this one refuses to fly it twice");
  };

  if (mine_.stage == kFlying) {
    if (const std::uint64_t other = held_by_other(mine_.id))
      return refuse("agent id " + std::to_string(mine_.id) + " is also flown by replica " +
                    hex(other) + ", which flew it first and keeps it: this replica (" +
                    hex(mine_.nonce) + ") yields and stops");
    return s;
  }
  if (mine_.stage == kConfirming) {
    if (const std::uint64_t other = held_by_other(mine_.id)) {
      if (fixed_ != 0) return already_held(other);
      mine_.id = 0;  // auto: rank again among the ids still free
      mine_.stage = kRanking;
      s.announce = true;
      return s;
    }
    if (now_s - confirm_since_s_ >= cfg_.confirm_s) {
      mine_.stage = kFlying;
      flying_since_s_ = now_s;
      s.taken = mine_.id;
      s.announce = true;
    }
    return s;
  }

  const auto confirm = [&](AgentId id) {
    mine_.id = id;
    mine_.stage = kConfirming;
    confirm_since_s_ = now_s;
    s.announce = true;
    return s;
  };
  if (fixed_ != 0) {
    if (const std::uint64_t other = held_by_other(fixed_)) return already_held(other);
    // A given id also waits for the whole swarm: a replica that has not discovered the others
    // would not know that its id is flown.
    if (ready && live() >= roster_.size()) return confirm(fixed_);
  } else {
    std::set<AgentId> held;
    std::vector<std::uint64_t> unranked{mine_.nonce};
    for (const auto& [nonce, c] : live_) {
      if (c.id != 0)  // confirming, flying, or given by hand
        held.insert(c.id);
      else
        unranked.push_back(nonce);
    }
    std::sort(unranked.begin(), unranked.end());
    std::vector<AgentId> free;
    for (AgentId id : roster_)
      if (!held.count(id)) free.push_back(id);
    const auto rank = static_cast<std::size_t>(
        std::find(unranked.begin(), unranked.end(), mine_.nonce) - unranked.begin());
    if (ready && rank >= free.size())
      return refuse("more replicas than the swarm's " + std::to_string(mine_.expected) +
                    " agents (heard " + std::to_string(live()) +
                    "): this one is left without an id and stops; set QSWARM_AGENTS to the "
                    "number of agent replicas");
    if (ready && live() == roster_.size()) return confirm(free[rank]);
  }
  if (now_s - start_s_ > cfg_.timeout_s)
    return refuse("heard " + std::to_string(live()) + " of " + std::to_string(mine_.expected) +
                  " replicas after " + std::to_string(static_cast<int>(cfg_.timeout_s)) +
                  " s: is QSWARM_AGENTS the number of agent replicas? (If it is and the "
                  "replicas all run: with some 30 or more containers on one host, the host's "
                  "neighbour table may overflow, see dmesg and README \"Docker compose\")");
  return s;
}

}  // namespace qswarm
