#pragma once

#include <string>

#include "common/core/math.hpp"
#include "common/core/topology.hpp"

namespace qswarm {

// An insider with valid credentials that lies: it tells its neighbours a consensus state of its
// choosing every tick while the others run their laws. The lockstep oracle (swarm-preview --liar,
// the resilient law's tests) and the in-process swarm (a lying agent over the in-memory bus) both
// take one.
struct Liar {
  enum class Kind {
    kConstant,  // claims `value`, always
    kDrift,  // claims its initial state + value * t (value in m/s): slow enough to look like motion
    kSplit,  // claims +value to even ids and -value to odd ids (a transport that lets an
             // agent tell each neighbour something else; DDS does not: one sample for all)
  };
  AgentId id = 0;
  Kind kind = Kind::kConstant;
  Vec3 value = Vec3::Zero();
  // What it tells `to` at time t, given its initial state.
  Vec3 claim(AgentId to, const Vec3& q0, double t_s) const;
};
std::string to_string(Liar::Kind k);  // constant, drift, split
Liar::Kind parse_liar_kind(const std::string& s);
// "ID:KIND[:X,Y,Z]" (swarm-preview --liar): without X,Y,Z the value is kDefaultLie (constant,
// split) or kDefaultDrift_mps (drift). std::invalid_argument saying what was expected.
Liar parse_liar(const std::string& text);
inline const Vec3 kDefaultLie(1000.0, 1000.0, 1000.0);
inline const Vec3 kDefaultDrift_mps(0.5, 0.5, 0.5);

}  // namespace qswarm
