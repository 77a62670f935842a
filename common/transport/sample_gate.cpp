#include "common/transport/sample_gate.hpp"

namespace qswarm {

SampleGate::Result SampleGate::admit(const StateMessage& m, const std::string& why) {
  Result r;
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
