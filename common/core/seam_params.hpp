#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace qswarm {

// One parameter a law or a plant takes: a scenario names it (`law_params`, `plant_params`),
// validated against [min, max] (and whole numbers where `integer`), `fallback` when unnamed.
struct SeamParam {
  std::string name;
  double min = 0.0;
  double max = 0.0;
  double fallback = 0.0;
  bool integer = false;
  std::string doc;  // one line: what it means, with its unit
};

// Every parameter of `params`, the given ones checked (an unknown name, a value out of range or
// not whole where it must be: std::invalid_argument naming `field`["name"] of `owner`, e.g. "law
// metropolis"), the rest at their fallback.
std::map<std::string, double> resolve_seam_params(const std::vector<SeamParam>& params,
                                                  const std::map<std::string, double>& given,
                                                  const std::string& field,
                                                  const std::string& owner);

// Why a spec's parameter list breaks the seam's rules (a name empty or twice, a fallback out of
// its range), or empty.
std::string seam_params_problem(const std::vector<SeamParam>& params);

// The FNV-1a hash of a name, never 0: what a sample says of the law that sent it (law_tag).
std::uint32_t seam_tag(const std::string& name);

}  // namespace qswarm
