#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "common/core/seam_params.hpp"
#include "common/core/update_law.hpp"

namespace qswarm {

// One parameter a law takes, named in a scenario's `law_params`.
using LawParam = SeamParam;

// The promises a law makes, which the record judges and `swarm check-law` flies it through. A law
// claims only what holds on a graph the scenario's topology keeps connected.
struct LawClaims {
  // The agents meet: disagreement falls below the judge's tolerance.
  bool agreement = true;
  // They meet at the exact average of the initial states, under loss, delay, cuts, kill and
  // restart (not only in lockstep).
  bool exact_average = false;
  // Honest agents stay inside the range of their initial values, coordinate by coordinate,
  // whatever up to F (the law's parameter "f") liars say, on an (F+1, F+1)-robust graph.
  bool honest_hull = false;
  // With collision avoidance on, quadcopters flying it keep the safe distance (avoidance sits
  // between the law and the plant, so a law keeps this unless it drives them through it).
  bool separation = true;
};

// A law as the rest of the project sees it: everything a scenario, an agent process, the record
// and the tools need, from one file per law (common/laws/) and one line in common/laws/laws.inc.
struct LawSpec {
  std::string name;                  // as scenarios and the record spell it: "edge-flow"
  std::vector<std::string> aliases;  // other spellings accepted ("edge_flow")
  std::string summary;               // one line for `swarm laws` and `swarm inspect`
  std::vector<LawParam> params;
  LawClaims claims;
  // The most doubles its payload (NeighborView::payload) carries, at most kMaxLawPayload: a sample
  // with more is refused on arrival, before the law sees it.
  std::size_t payload_max = 0;
  std::function<std::unique_ptr<UpdateLaw>(AgentId, const Vec3&, const LawConfig&)> make;
};

// Every registered law, in the order of common/laws/laws.inc.
const std::vector<LawSpec>& registered_laws();
// The law named `name` (or one of its aliases); throws std::invalid_argument naming the laws there
// are.
const LawSpec& find_law(const std::string& name);
// "edge-flow, laplacian, w-msr, ..." for messages.
std::string law_names();
// What a sample says of the law that sent it: a hash of the name, never 0.
std::uint32_t law_tag(const std::string& name);
// Every parameter of `spec`, the given ones checked (an unknown name, a value out of range or not
// whole where it must be: std::invalid_argument naming `field`["name"]), the rest at their
// fallback.
std::map<std::string, double> resolve_law_params(const LawSpec& spec,
                                                 const std::map<std::string, double>& given,
                                                 const std::string& field = "law_params");

// The F that cfg's law claims to keep honest agents in their initial range against (its "f"); -1
// when the law makes no such claim.
int honest_hull_f(const LawConfig& cfg);

}  // namespace qswarm
