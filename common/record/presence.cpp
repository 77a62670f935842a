#include "common/record/presence.hpp"

#include <algorithm>

namespace qswarm {

Presence::Presence(const std::vector<AgentId>& ids, double timeout_s, std::uint32_t record_every)
    : timeout_s_(timeout_s), every_(std::max<std::uint32_t>(1, record_every)) {
  for (const AgentId id : ids) tracks_[id];
}

Presence::Change Presence::on_sample(const StateMessage& m, double now_s) {
  const auto it = tracks_.find(m.view.id);
  if (it == tracks_.end()) {
    return strangers_.insert(m.view.id).second ? Change::kStranger : Change::kStrangerAgain;
  }
  Track& a = it->second;
  Change change = Change::kNone;
  if (!a.seen) {
    a.seen = true;
    a.first = m;
    change = Change::kJoin;
  } else if (!a.present && m.phase != Phase::kStopping) {
    change = Change::kRejoin;
  }
  // Agents send every k-th sample (seq a multiple of k) and their goodbye: a gap is a multiple of k
  // that never came. Not across the start: which ticks an agent records is set at its first tick,
  // whose number skips past the ones its barrier used.
  const bool started = m.phase == Phase::kRunning && a.last.phase != Phase::kRunning;
  if (a.samples > 0 && m.incarnation == a.last.incarnation && m.seq % every_ == 0 &&
      a.last.seq % every_ == 0 && m.seq > a.last.seq + every_ && !started) {
    a.gaps += (m.seq - a.last.seq) / every_ - 1;
  }
  if (m.phase == Phase::kStopping && a.present) change = Change::kDepart;
  a.present = m.phase != Phase::kStopping;
  // A goodbye that counts law ticks ran too: with one record in k ticks, an agent stopped within
  // its first k ticks is heard only at the barrier and saying goodbye.
  a.ran = a.ran || m.phase == Phase::kRunning || m.view.seq >= 1;
  a.last = m;
  a.last_heard_s = now_s;
  ++a.samples;
  return change;
}

std::vector<AgentId> Presence::expire(double now_s) {
  std::vector<AgentId> gone;
  for (auto& [id, a] : tracks_) {
    if (a.present && a.seen && now_s - a.last_heard_s > timeout_s_) {
      a.present = false;
      gone.push_back(id);
    }
  }
  return gone;
}

bool Presence::running(AgentId id) const {
  const Track& t = tracks_.at(id);
  return t.present && t.last.phase == Phase::kRunning;
}

std::size_t Presence::present_count() const {
  std::size_t n = 0;
  for (const auto& [id, a] : tracks_) n += a.present ? 1 : 0;
  return n;
}

std::size_t Presence::seen_count() const {
  std::size_t n = 0;
  for (const auto& [id, a] : tracks_) n += a.seen ? 1 : 0;
  return n;
}

}  // namespace qswarm
