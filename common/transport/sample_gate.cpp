#include "common/transport/sample_gate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "common/core/law_registry.hpp"

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

bool SampleGate::more_than_sent(std::uint64_t samples, double since_s) {
  return static_cast<double>(samples) >
         static_cast<double>(kJumpSlack) + kMaxRatePerS * std::max(0.0, since_s);
}

bool SampleGate::far_ahead(const StateMessage& a, const StateMessage& b, double since_s) {
  if (a.incarnation != b.incarnation || a.seq <= b.seq) return false;
  return more_than_sent(a.seq - b.seq, since_s);
}

bool SampleGate::jumps(const StateMessage& m, const Agent& a, std::int64_t now_wall_ns) const {
  if (now_wall_ns <= 0 || a.held_at_ns <= 0) return false;
  return far_ahead(m, a.held, static_cast<double>(now_wall_ns - a.held_at_ns) * 1e-9);
}

bool SampleGate::behind(const StateMessage& m, const Agent& a, std::int64_t now_wall_ns) const {
  if (now_wall_ns <= 0 || a.held_at_ns <= 0) return false;
  return far_ahead(a.held, m, static_cast<double>(now_wall_ns - a.held_at_ns) * 1e-9);
}

bool SampleGate::implausible(const StateMessage& m, std::int64_t now_wall_ns) {
  if (now_wall_ns <= 0) return false;
  return more_than_sent(m.seq, static_cast<double>(now_wall_ns - m.incarnation) * 1e-9);
}

bool SampleGate::interleaved(Agent& a, const WriterId& w) {
  const std::uint64_t h = w.hash();
  ++a.samples;
  Agent::Seen* slot = nullptr;
  for (Agent::Seen& s : a.seen)
    if (s.at != 0 && s.writer == h) slot = &s;
  if (slot && a.last_writer != h && a.samples - slot->at <= kRecentSamples) ++a.returns;
  if (!slot) {
    // The writer heard longest ago makes room, never the owner: a forger rotating more writers
    // than there are slots would otherwise push the owner out before it is heard again.
    const std::uint64_t owner = a.owner.hash();
    for (Agent::Seen& s : a.seen)
      if (s.writer != owner && (!slot || s.at < slot->at)) slot = &s;
    slot->writer = h;
  }
  slot->at = a.samples;
  a.last_writer = h;
  return a.returns >= kReturns;
}

std::uint8_t SampleGate::notice_bits(AgentId id, std::uint8_t kinds) {
  std::uint8_t& held = suspects_[id];
  const std::uint8_t fresh = static_cast<std::uint8_t>(kinds & ~held);
  held = static_cast<std::uint8_t>(held | kinds);
  return fresh;
}

bool SampleGate::notice(AgentId id, std::uint8_t kinds) { return notice_bits(id, kinds) != 0; }

void ArrivalAges::add(std::int64_t age_ns) {
  if (age_ns < 0) {
    ++early;
    return;
  }
  const double us = static_cast<double>(age_ns) * 1e-3;
  const int bin =
      us < 10.0 ? 0
                : std::min(kBins - 1, 1 + static_cast<int>(std::floor(4.0 * std::log2(us / 10.0))));
  ++count[static_cast<std::size_t>(bin)];
}

std::uint64_t ArrivalAges::total() const {
  std::uint64_t n = 0;
  for (const std::uint64_t c : count) n += c;
  return n;
}

double ArrivalAges::upper_edge_ms(int bin) {
  if (bin >= kBins - 1) return std::numeric_limits<double>::infinity();
  return 0.01 * std::exp2(0.25 * bin);
}

double ArrivalAges::quantile_ms(double q) const {
  const std::uint64_t n = total();
  if (n == 0 || !(q > 0.0)) return -1.0;
  const auto want = std::max<std::uint64_t>(
      1, static_cast<std::uint64_t>(std::ceil(std::min(q, 1.0) * static_cast<double>(n))));
  std::uint64_t seen = 0;
  for (int b = 0; b < kBins; ++b) {
    seen += count[static_cast<std::size_t>(b)];
    if (seen >= want) return upper_edge_ms(b);
  }
  return upper_edge_ms(kBins - 1);
}

void SampleGate::count_accepted(const StateMessage& m, std::int64_t now_wall_ns) {
  ++counters_.received;
  if (now_wall_ns > 0 && m.wall_ns > 0) counters_.ages.add(now_wall_ns - m.wall_ns);
}

ExpectedLaw expected_law(const std::string& law_name) {
  return {law_tag(law_name), find_law(law_name).payload_max};
}

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
  if (why.empty() && law_.tag != 0 &&
      (m.view.law != law_.tag || m.view.payload.size() > law_.payload_max)) {
    return admit(m,
                 m.view.law != law_.tag ? "a sample of another law"
                                        : "law payload longer than the law's bound",
                 0, writer);
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
    count_accepted(m, now_wall_ns);
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
    // The owner's numbers far ahead of this writer's in the same life: the owner forged them (a
    // relay heard before the real agent); this writer takes the agent at once.
    // Only when the owner's number is more than its life could have reached: a forger that
    // replays the real life with small numbers must otherwise take the agent as any other writer.
    const bool owner_jumped = behind(m, a, now_wall_ns) && implausible(a.held, now_wall_ns);
    if (owner_jumped) r.noticed |= notice_bits(m.view.id, kSequenceJump);
    // A jump against the held sample still counts toward a takeover: the held sample may be a
    // forger's, and the real agent's numbers far from it.
    if (!owner_jumped && ++a.contender_run < kTakeover)
      return refuse(jump ? "sequence number jumps far ahead of the agent's"
                         : "another writer holds this agent");
    // The owner went silent while this writer spoke, or forged its numbers: this writer takes the
    // agent over, and its own sequence from here (a restart, or the real agent after its forger
    // stopped).
    a.contender = a.owner;
    a.contender_run = 0;
    a.owner = writer;
    r.new_owner = true;
  }
  a.held = m;
  a.held_at_ns = now_wall_ns;
  count_accepted(m, now_wall_ns);
  return r;
}

void SampleGate::for_each_latest(AgentId self,
                                 const std::function<void(const StateMessage&)>& visit) const {
  for (const auto& [id, a] : agents_)
    if (id != self) visit(a.held);
}

}  // namespace qswarm
