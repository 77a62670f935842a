#include "common/transport/sample_gate.hpp"

namespace qswarm {

SampleGate::Result SampleGate::admit(const StateMessage& m, const std::string& why,
                                     std::int64_t now_wall_ns) {
  Result r;
  constexpr std::int64_t kClockSkewNs = 60'000'000'000;
  if (why.empty() && now_wall_ns > 0 && m.incarnation > now_wall_ns + kClockSkewNs) {
    return admit(m, "incarnation (start time) in the future", 0);
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
  auto it = latest_.find(m.view.id);
  if (it != latest_.end() && !is_newer(m, it->second)) {
    ++counters_.stale;
    r.verdict = Verdict::kStale;
    return r;
  }
  latest_[m.view.id] = m;
  ++counters_.received;
  return r;
}

std::vector<StateMessage> SampleGate::latest(AgentId self) const {
  std::vector<StateMessage> out;
  out.reserve(latest_.size());
  for (const auto& [id, m] : latest_)
    if (id != self) out.push_back(m);
  return out;
}

}  // namespace qswarm
