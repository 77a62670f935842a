#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/scenario/run_config.hpp"
#include "proto/scenario.pb.h"

namespace qswarm {

// Bad scenario input: the message names the field (and line for syntax) and what was expected.
class ScenarioError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A scenario file larger than this is refused unread (512 listed agents take about 40 KiB).
inline constexpr std::size_t kMaxScenarioBytes = 4u << 20;

// Overrides from the command line, applied before validation.
struct ScenarioOverrides {
  int agents = -1;         // --agents N: replace the agent list with N seeded random agents
  std::string law;         // --law: a registered law's name (swarm laws)
  std::string plant;       // --plant: a registered plant's name (swarm plants)
  std::int64_t seed = -1;  // --seed S
  double duration_s = -1;  // --duration S
  int domain_id = -1;      // --domain D
  std::string keystore;    // --secure DIR
};

// scenario_file.cpp: text <-> message.
scenario::Scenario parse_scenario_text(const std::string& text, const std::string& source);
scenario::Scenario read_scenario_file(const std::string& path);
std::string to_text(const scenario::Scenario& s);
// scenario_resolve.cpp: a pure function of the message and the overrides; every field is checked
// against a range a run can honour, and a bad one throws ScenarioError naming it.
RunConfig resolve_scenario(scenario::Scenario s, const ScenarioOverrides& o = {});
RunConfig load_scenario(const std::string& path, const ScenarioOverrides& o = {});
// A number as an error message quotes it (shortest form, as a person would type it).
std::string quoted_number(double v);

}  // namespace qswarm
