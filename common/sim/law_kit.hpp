#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "common/core/law_registry.hpp"

namespace qswarm {

// The conformance kit (`swarm check-law`): flies a law through the promises a law may claim
// (LawClaims), each in the in-process swarm (the agent runtime of the agent processes, the
// in-memory bus with the fault plan's loss, delay, cuts, kills and restarts, one manual clock),
// and reports which it keeps. A promise the law claims and breaks fails the kit; one it does not
// claim is measured and reported all the same.
struct KitRow {
  std::string promise;   // "agreement", "exact average", "honest hull", "separation"
  std::string flight;    // what was flown: "paper unweighted", "loss 30 %", ...
  bool claimed = false;  // the law claims it
  bool kept = false;
  std::string measured;  // what the flight measured, for people
};

struct KitReport {
  std::string law;
  std::vector<KitRow> rows;
  // Every promise the law claims was kept.
  bool passed() const;
  // A Markdown table, one row a flight.
  std::string table() const;
};

struct KitOptions {
  // The repository's scenarios/ (paper/, faults_six.txtpb, insider_seven.txtpb).
  std::filesystem::path scenarios = "scenarios";
  // Its parameters (unnamed ones: the law's defaults), as a scenario's law_params.
  std::map<std::string, double> params;
  // Off: the separation flight without collision avoidance, the control that shows the flight
  // can find a violation (claimed then by no law).
  bool avoidance = true;
};

// Flies `spec`'s law (built by the registered law of its name; its claims are the spec's, so a
// test can claim for a law what it does not keep). Throws ScenarioError when a scenario of the
// kit cannot be read or the parameters are refused.
KitReport check_law(const LawSpec& spec, const KitOptions& options);

}  // namespace qswarm
