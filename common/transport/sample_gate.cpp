#include "common/transport/sample_gate.hpp"

#include <algorithm>
#include <cstdio>

namespace qswarm {

bool WriterId::known() const {
  for (const std::uint8_t b : bytes)
    if (b != 0) return true;
  return false;
}

std::string WriterId::str() const {
  std::string out;
  char buf[4];
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    if (i == 12) out += '.';  // prefix.entity
    std::snprintf(buf, sizeof buf, "%02x", bytes[i]);
    out += buf;
  }
  return out;
}

std::uint64_t WriterId::hash() const {
  std::uint64_t h = 1469598103934665603ULL;  // FNV-1a
  for (const std::uint8_t b : bytes) h = (h ^ b) * 1099511628211ULL;
  return h;
}

bool SampleGate::jumps(const StateMessage& m, const Agent& a, std::int64_t now_wall_ns) const {
  const StateMessage& held = a.held;
  if (now_wall_ns <= 0 || a.held_at_ns <= 0 || m.incarnation != held.incarnation ||
      m.seq <= held.seq)
    return false;
  const double since_s =
      static_cast<double>(std::max<std::int64_t>(0, now_wall_ns - a.held_at_ns)) * 1e-9;
  return static_cast<double>(m.seq - held.seq) >
         static_cast<double>(kJumpSlack) + kMaxRatePerS * since_s;
}

bool SampleGate::interleaved(Agent& a, const WriterId& w) {
  a.recent[a.recent_n % a.recent.size()] = w.hash();
  ++a.recent_n;
  const std::size_t n = std::min(a.recent_n, a.recent.size());
  int changes = 0;
  for (std::size_t k = 1; k < n; ++k) {
    const std::size_t i = (a.recent_n - n + k) % a.recent.size();
    const std::size_t j = (a.recent_n - n + k - 1) % a.recent.size();
    changes += a.recent[i] != a.recent[j] ? 1 : 0;
  }
  return changes >= kInterleaved;
}

std::uint8_t SampleGate::notice_bits(AgentId id, std::uint8_t kinds) {
  std::uint8_t& held = suspects_[id];
  const std::uint8_t fresh = static_cast<std::uint8_t>(kinds & ~held);
  held = static_cast<std::uint8_t>(held | kinds);
  return fresh;
}

bool SampleGate::notice(AgentId id, std::uint8_t kinds) { return notice_bits(id, kinds) != 0; }

SampleGate::Result SampleGate::admit(const StateMessage& m, const std::string& why,
                                     std::int64_t now_wall_ns, const WriterId& writer) {
  Result r;
  constexpr std::int64_t kClockSkewNs = 60'000'000'000;
  if (why.empty() && now_wall_ns > 0 && m.incarnation > now_wall_ns + kClockSkewNs) {
    // It would lock the real agent out as "stale" for the rest of the run.
    Result f = admit(m, "incarnation (start time) in the future", 0, writer);
    if (f.verdict == Verdict::kInvalid) f.noticed = notice_bits(m.view.id, kFutureIncarnation);
    return f;
  }
  if (run_id_ != 0 && m.run_id != run_id_) {
    ++counters_.foreign;
    r.verdict = Verdict::kForeign;
    r.first_from = foreign_runs_.insert(m.run_id).second;
    return r;
  }
  if (!why.empty()) {
    ++counters_.dropped;
    r.verdict = Verdict::kInvalid;
    r.why = why;
    r.first_from = warned_.insert(m.view.id).second;
    return r;
  }
  const auto refuse = [&](const char* what) {
    ++counters_.contested;
    r.verdict = Verdict::kContested;
    r.why = what;
    return r;
  };
  auto it = agents_.find(m.view.id);
  if (it == agents_.end()) {
    Agent& a = agents_[m.view.id];
    a.held = m;
    a.held_at_ns = now_wall_ns;
    a.owner = writer;
    interleaved(a, writer);
    ++counters_.received;
    return r;
  }
  Agent& a = it->second;
  if (interleaved(a, writer)) r.noticed |= notice_bits(m.view.id, kTwoWriters);
  const bool jump = jumps(m, a, now_wall_ns);
  if (jump) r.noticed |= notice_bits(m.view.id, kSequenceJump);
  if (writer == a.owner) {
    a.contender_run = 0;
    if (jump) return refuse("sequence number jumps far ahead of the agent's");
    if (!is_newer(m, a.held)) {
      ++counters_.stale;
      r.verdict = Verdict::kStale;
      return r;
    }
  } else {
    if (!(writer == a.contender)) {
      a.contender = writer;
      a.contender_run = 0;
    }
    // A jump against the held sample still counts toward a takeover: the held sample may be a
    // forger's, and the real agent's numbers far from it.
    if (++a.contender_run < kTakeover)
      return refuse(jump ? "sequence number jumps far ahead of the agent's"
                         : "another writer holds this agent");
    // The owner went silent while this writer spoke: it takes the agent over, and its own
    // sequence from here (a restart, or the real agent after its forger stopped).
    a.contender = a.owner;
    a.contender_run = 0;
    a.owner = writer;
    r.new_owner = true;
  }
  a.held = m;
  a.held_at_ns = now_wall_ns;
  ++counters_.received;
  return r;
}

std::vector<StateMessage> SampleGate::latest(AgentId self) const {
  std::vector<StateMessage> out;
  out.reserve(agents_.size());
  for (const auto& [id, a] : agents_)
    if (id != self) out.push_back(a.held);
  return out;
}

}  // namespace qswarm
