#include "common/runtime/agent_lifecycle.hpp"

#include <cmath>

#include <algorithm>
#include <bit>
#include <cstdio>

#include "common/transport/stamp_slack.hpp"
#include "common/transport/state_message.hpp"

namespace qswarm {

const char* to_string(LifePhase p) {
  switch (p) {
    case LifePhase::kJoinWait:
      return "join-wait";
    case LifePhase::kWaiting:
      return "waiting";
    case LifePhase::kReady:
      return "ready";
    case LifePhase::kRunning:
      return "running";
    case LifePhase::kStopping:
      return "stopping";
  }
  return "?";
}

AgentLifecycle::AgentLifecycle(LifecycleConfig cfg, double now_wall_s)
    : cfg_(std::move(cfg)),
      born_s_(now_wall_s),
      phase_(cfg_.join_at_s ? LifePhase::kJoinWait : LifePhase::kWaiting),
      next_progress_s_(now_wall_s + kProgressPeriodS) {
  std::sort(cfg_.kill_at_s.begin(), cfg_.kill_at_s.end());
  std::sort(cfg_.roster.begin(), cfg_.roster.end());
  if (!cfg_.roster.empty() && !cfg_.join_at_s) {
    known_.assign((cfg_.roster.size() + 7) / 8, 0);
    ready_.assign(known_.size(), 0);
    set_bit(known_, cfg_.self);
    for (const AgentId p : cfg_.barrier_peers) set_bit(known_, p);
  }
}

bool AgentLifecycle::set_bit(std::vector<std::uint8_t>& bits, AgentId id) const {
  const auto it = std::lower_bound(cfg_.roster.begin(), cfg_.roster.end(), id);
  if (it == cfg_.roster.end() || *it != id) return false;
  const auto k = static_cast<std::size_t>(it - cfg_.roster.begin());
  const auto was = bits[k / 8];
  bits[k / 8] = static_cast<std::uint8_t>(was | (1u << (k % 8)));
  return bits[k / 8] != was;
}

bool AgentLifecycle::merge(const PeerStatus& p, double now) {
  if (known_.empty()) return false;
  const double ready_at_was = ready_at_;
  bool grew = set_bit(known_, p.id);
  if (p.phase == Phase::kReady || p.phase == Phase::kRunning) grew = set_bit(ready_, p.id) || grew;
  // Bitsets of another length (another roster: a sender the run id did not keep out) are
  // ignored; bits past the roster's end are cleared.
  if (p.known.size() == known_.size() && p.ready.size() == ready_.size()) {
    const std::size_t n = cfg_.roster.size();
    const auto tail = static_cast<std::uint8_t>(n % 8 == 0 ? 0xffu : (1u << (n % 8)) - 1u);
    for (std::size_t k = 0; k < known_.size(); ++k) {
      const std::uint8_t mask = k + 1 == known_.size() ? tail : 0xff;
      const auto known = static_cast<std::uint8_t>((known_[k] | p.known[k]) & mask);
      const auto ready = static_cast<std::uint8_t>((ready_[k] | p.ready[k]) & mask);
      grew = grew || known != known_[k] || ready != ready_[k];
      known_[k] = known;
      ready_[k] = ready;
    }
    // Every process reads the same time line, so no agent turned ready after now: a later
    // instant is a lie that would hold the start back.
    if (std::isfinite(p.ready_at_s))
      ready_at_ = std::max(ready_at_, std::min(p.ready_at_s, now + cfg_.shared_origin_s));
  }
  return grew || ready_at_ != ready_at_was;
}

bool AgentLifecycle::all_known_ready() const {
  for (std::size_t k = 0; k < known_.size(); ++k)
    if ((known_[k] & ~ready_[k]) != 0) return false;
  return true;
}

double AgentLifecycle::go_delay_s() const {
  const auto hops = static_cast<double>(std::min<std::size_t>(cfg_.roster.size(), kGoHops));
  return hops * cfg_.announce_period_s;
}

std::size_t AgentLifecycle::count(const std::vector<std::uint8_t>& bits) const {
  std::size_t n = 0;
  for (const std::uint8_t b : bits) n += static_cast<std::size_t>(std::popcount(b));
  return n;
}

LifecycleStep AgentLifecycle::step(double now, const std::vector<PeerStatus>& peers,
                                   int matched_readers, double agent_time_s,
                                   bool recorder_confirmed) {
  switch (phase_) {
    case LifePhase::kJoinWait:
      return join_wait(now, peers);
    case LifePhase::kWaiting:
    case LifePhase::kReady:
      return barrier(now, peers, matched_readers, recorder_confirmed);
    case LifePhase::kRunning:
      return running(now, agent_time_s);
    case LifePhase::kStopping:
      break;
  }
  LifecycleStep s;
  s.stop = true;
  s.wake_at_s = now;
  return s;
}

void AgentLifecycle::enter_running(double now, LifecycleStep& s, double start_time_s) {
  phase_ = LifePhase::kRunning;
  discovery_s_ = now - born_s_;
  // The first tick on the shared grid at or after now.
  const double grid = std::ceil((now + cfg_.tick_origin_s) / cfg_.tick_wall_s) * cfg_.tick_wall_s;
  pacer_.emplace(grid - cfg_.tick_origin_s, cfg_.tick_wall_s);
  s.start = true;
  s.start_time_s = start_time_s;
  // Kills planned before this life began were its predecessors'.
  while (next_kill_ < cfg_.kill_at_s.size() && cfg_.kill_at_s[next_kill_] < start_time_s)
    ++next_kill_;
  s.wake_at_s = now;  // the first tick is due at once
}

AgentLifecycle::SwarmClock AgentLifecycle::swarm_clock(const std::vector<PeerStatus>& peers) const {
  std::vector<double> t;
  for (const PeerStatus& p : peers)
    if (p.phase == Phase::kRunning && std::isfinite(p.stamp_s) &&
        (cfg_.duration_s <= 0.0 || p.stamp_s <= cfg_.duration_s + kStampSlackS))
      t.push_back(p.stamp_s);
  SwarmClock clock;
  if (t.empty()) return clock;
  std::sort(t.begin(), t.end());
  // The upper median: a peer killed without a word keeps its last stamp in the gate, so old
  // stamps may be as many as the live ones; the swarm's clock is the newest of them.
  const double median = t[t.size() / 2];
  for (const double v : t)
    if (v <= median + kStampSlackS) clock.t = v;
  for (const double v : t) clock.telling += v <= clock.t && v >= clock.t - kStampSlackS;
  return clock;
}

LifecycleStep AgentLifecycle::join_wait(double now, const std::vector<PeerStatus>& peers) {
  LifecycleStep s;
  const double swarm_t = swarm_clock(peers).t;
  s.swarm_time_s = swarm_t;
  const double join_at = *cfg_.join_at_s;
  const bool timed_out = now - born_s_ > join_at / cfg_.time_scale + cfg_.join_timeout_s;
  if (swarm_t >= join_at || timed_out) {
    if (timed_out && swarm_t < join_at) {
      char buf[160];
      std::snprintf(buf, sizeof buf,
                    "join: the swarm's clock never reached %.2f s (at %.2f s), joining now",
                    join_at, swarm_t);
      s.warning = buf;
    }
    enter_running(now, s, std::max(0.0, swarm_t));
    return s;
  }
  s.wake_at_s = now + cfg_.announce_period_s;
  return s;
}

LifecycleStep AgentLifecycle::barrier(double now, const std::vector<PeerStatus>& peers,
                                      int matched_readers, bool recorder_confirmed) {
  LifecycleStep s;
  std::size_t heard = 0, ready = 0;
  bool peer_running = false, learnt = false;
  const SwarmClock clock = swarm_clock(peers);
  for (const PeerStatus& p : peers) {
    learnt = merge(p, now) || learnt;
    // Any agent of the run that runs: a running agent sends no bitsets, so one that started the
    // moment its go came due passes on no more news.
    peer_running = peer_running || p.phase == Phase::kRunning;
    if (!cfg_.barrier_peers.count(p.id)) continue;
    ++heard;
    ready += (p.phase == Phase::kReady || p.phase == Phase::kRunning) ? 1 : 0;
  }
  // A swarm long in flight does not wait for this agent: it joins now, on the swarm's clock, when
  // two running peers tell it that clock (one, where it has a single barrier peer): a lone
  // sample, a forger's, releases no barrier.
  if (clock.t / cfg_.time_scale > kLateAfterWallS &&
      clock.telling >=
          std::min<std::size_t>(2, std::max<std::size_t>(1, cfg_.barrier_peers.size()))) {
    s.late = true;
    s.swarm_time_s = clock.t;
    enter_running(now, s, clock.t);
    return s;
  }
  const std::size_t expected = cfg_.barrier_peers.size();
  const bool all_heard = heard >= expected && matched_readers >= cfg_.min_matched_readers &&
                         (recorder_confirmed || !cfg_.wait_recorder);
  if (all_heard && !known_.empty() && !own_ready_at_) {
    own_ready_at_ = now + cfg_.shared_origin_s;
    set_bit(ready_, cfg_.self);
    ready_at_ = std::max(ready_at_, *own_ready_at_);
    learnt = true;
  }
  // Every agent that finds its part of the swarm ready finds the same last ready instant, so all
  // start at the same go, however many hops the news took to reach each. Fixed once found: a
  // later claim cannot move it.
  if (!go_ && !known_.empty() && all_known_ready())
    go_ = ready_at_ - cfg_.shared_origin_s + go_delay_s();
  // An agent that runs started at the go (or timed out): waiting longer would only add skew.
  if (all_heard && ready >= expected && (known_.empty() || (go_ && now >= *go_) || peer_running)) {
    enter_running(now, s, 0.0);
    return s;
  }
  if (now - born_s_ > cfg_.start_timeout_s) {
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "start timeout: %zu of %zu peers ready, %zu of %zu agents known to start ready, "
                  "starting anyway",
                  ready, expected, count(ready_), count(known_));
    s.warning = buf;
    enter_running(now, s, 0.0);
    return s;
  }
  if (now >= next_progress_s_) {
    // A large swarm can wait here for a long time: say what for, so a stuck start is never silent.
    char buf[260];
    std::snprintf(buf, sizeof buf,
                  "at the start barrier after %.0f s: %zu of %zu peers heard, %zu ready, %d of %d "
                  "readers matched, recorder %s; %zu of %zu agents known to start are ready",
                  now - born_s_, heard, expected, ready, matched_readers, cfg_.min_matched_readers,
                  !cfg_.wait_recorder  ? "not awaited"
                  : recorder_confirmed ? "confirmed"
                                       : "not confirmed",
                  count(ready_), count(known_));
    s.progress = buf;
    next_progress_s_ = now + kProgressPeriodS;
  }
  const LifePhase was = phase_;
  phase_ = all_heard ? LifePhase::kReady : LifePhase::kWaiting;
  if (phase_ != was) {  // peers learn of a change at once
    next_announce_s_ = now;
    ready_burst_left_ = all_heard ? kReadyAnnouncements - 1 : 0;  // this one is the first
  } else if (learnt && all_heard) {
    // The flood moves about a hop per announce period: a ready agent passes on what it learnt at
    // once, but no sooner than an announce period after its last announcement (the process polls
    // more often than that); what it learns next, or its beacon, repeats it.
    next_announce_s_ =
        std::min(next_announce_s_, std::max(now, last_announce_s_ + cfg_.announce_period_s));
  }
  // Announcements are due on their own schedule, however often the caller polls: the process
  // polls at least every 50 ms to see a stop request, which at 256 agents made every agent at the
  // barrier announce 20 times a second.
  if (now >= next_announce_s_) {
    s.announce = all_heard ? Phase::kReady : Phase::kWaiting;
    double period = cfg_.waiting_period_s;
    if (ready_burst_left_ > 0) {
      --ready_burst_left_;
      period = cfg_.announce_period_s;
    }
    next_announce_s_ = now + period;
    last_announce_s_ = now;
  }
  s.wake_at_s = all_heard ? now + cfg_.announce_period_s : next_announce_s_;
  if (all_heard && go_) s.wake_at_s = std::max(now, std::min(s.wake_at_s, *go_));
  return s;
}

LifecycleStep AgentLifecycle::running(double now, double agent_time_s) {
  LifecycleStep s;
  TickPacer& pacer = *pacer_;
  if (now - pacer.start_s() > cfg_.max_wall_s) {
    s.warning = "max wall time reached, stopping";
    s.stop = true;
    phase_ = LifePhase::kStopping;
    s.wake_at_s = now;
    return s;
  }
  if (pacer.due(now)) {
    if (next_kill_ < cfg_.kill_at_s.size() && agent_time_s >= cfg_.kill_at_s[next_kill_]) {
      s.kill = true;
      s.wake_at_s = now;
      return s;
    }
    pacer.on_tick(now);
    s.ticks = 1;
  }
  s.wake_at_s = pacer.next_due_s();
  return s;
}

}  // namespace qswarm
