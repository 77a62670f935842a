#include "common/transport/state_message.hpp"

#include <algorithm>
#include <cmath>

namespace qswarm {

std::string check_message(const StateMessage& m) {
  if (m.view.id == 0) return "agent id 0";
  if (std::string why = check_view(m.view); !why.empty()) return why;
  const auto bad = [](const auto& x, double limit) {
    return !x.allFinite() || x.cwiseAbs().maxCoeff() > limit;
  };
  if (bad(m.p_W, 1e6)) return "position not finite or beyond 1000 km";
  if (bad(m.v_W, 1e3)) return "velocity not finite or above 1 km/s";
  if (!m.q_WB.coeffs().allFinite() || std::abs(m.q_WB.norm() - 1.0) > 1e-3) {
    return "orientation not a unit quaternion";
  }
  if (!m.rotors_radps.allFinite() || (m.rotors_radps.array() < 0.0).any() ||
      (m.rotors_radps.array() > 1e4).any()) {
    return "rotor speeds not finite or outside [0, 1e4] rad/s";
  }
  if (!std::isfinite(m.stamp_s) || m.stamp_s < 0.0 || m.stamp_s > 1e7)
    return "stamp not finite or outside [0, 1e7] s";
  if (m.mode != PoseKind::kPosition && m.mode != PoseKind::kOriented) return "unknown mode";
  if (m.phase > Phase::kReady) return "unknown phase";
  if (m.strangers.size() > kMaxStrangers) return "too many strangers reported";
  if (m.suspects.size() > kMaxSuspects) return "too many suspects reported";
  if (m.barrier_known.size() > kMaxBarrierBytes || m.barrier_ready.size() > kMaxBarrierBytes)
    return "start barrier bitset too long";
  if (!std::isfinite(m.barrier_ready_at_s) || std::abs(m.barrier_ready_at_s) > 1e12)
    return "start barrier instant not finite or absurd";
  if (m.host.size() > kMaxHostBytes || std::any_of(m.host.begin(), m.host.end(), [](char c) {
        return c < 0x20 || c > 0x7e || c == ',' || c == '"';
      }))
    return "host too long or not printable";
  for (const Suspect& s : m.suspects)
    if (s.id == 0 || s.kinds == 0 || (s.kinds & ~kAllSuspectKinds) != 0) return "suspect invalid";
  for (const auto* links : {&m.links, &m.initial_links}) {
    for (const auto& [peer, w] : *links) {
      if (!std::isfinite(w) || w < 0.0 || w > 1e9 || peer == m.view.id) return "link invalid";
    }
  }
  return {};
}

const char* suspect_name(SuspectKind k) {
  switch (k) {
    case kTwoWriters:
      return "two_writers";
    case kSequenceJump:
      return "sequence_jump";
    case kFutureIncarnation:
      return "future_incarnation";
    case kBoundElsewhere:
      return "bound_elsewhere";
  }
  return "unknown";
}

const char* suspect_text(SuspectKind k) {
  switch (k) {
    case kTwoWriters:
      return "its samples came from two writers at once (an impersonator, or a relay of it)";
    case kSequenceJump:
      return "a sample jumped far beyond its sequence numbers (forged as newer; refused)";
    case kFutureIncarnation:
      return "a sample claimed a start time in the future (forged as a restart; refused)";
    case kBoundElsewhere:
      return "a participant whose certificate names another agent published as it (refused)";
  }
  return "unknown";
}

bool mentions(const StateMessage& m, AgentId id) {
  const auto in = [id](const auto& entries) {
    return std::any_of(entries.begin(), entries.end(),
                       [id](const FlowEntry& e) { return e.peer == id; });
  };
  return std::any_of(m.links.begin(), m.links.end(),
                     [id](const auto& l) { return l.first == id; }) ||
         in(m.view.flows) || in(m.view.copies) ||
         std::find(m.view.asking.begin(), m.view.asking.end(), id) != m.view.asking.end();
}

}  // namespace qswarm
