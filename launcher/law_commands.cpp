// `swarm laws` (the registered agreement laws, their parameters and claims), `swarm plants` (the
// registered plants and their parameters) and `swarm check-law NAME` (the conformance kit:
// common/sim/law_kit.hpp).
#include <CLI/CLI.hpp>

#include <iostream>
#include <memory>
#include <string>

#include "common/core/law_registry.hpp"
#include "common/core/plant.hpp"
#include "common/scenario/scenario.hpp"
#include "common/sim/law_kit.hpp"
#include "launcher/commands.hpp"

namespace qswarm {
namespace {

std::string claims_text(const LawClaims& c) {
  std::string out;
  const auto add = [&](bool on, const char* what) {
    if (on) out += (out.empty() ? "" : ", ") + std::string(what);
  };
  add(c.agreement, "agreement");
  add(c.exact_average, "exact average");
  add(c.honest_hull, "honest hull");
  add(c.separation, "separation");
  return out.empty() ? "none" : out;
}

void print_params(const std::vector<SeamParam>& params, const char* field) {
  for (const SeamParam& p : params) {
    std::cout << "  " << field << " \"" << p.name << "\": " << p.doc << " (" << p.min << " to "
              << p.max << (p.integer ? ", whole" : "") << ", default " << p.fallback << ")\n";
  }
}

int list_laws() {
  for (const LawSpec& s : registered_laws()) {
    std::cout << s.name << ": " << s.summary << "\n  claims: " << claims_text(s.claims) << "\n";
    print_params(s.params, "law_params");
  }
  return 0;
}

int list_plants() {
  for (const PlantSpec& s : registered_plants()) {
    std::cout << s.name << ": " << s.summary << "\n  "
              << (s.follows_reference ? "follows the reference, collision avoidance on by default"
                                      : "is where its law puts it, no collision avoidance");
    if (s.min_physics_hz > 0.0) std::cout << ", rates.physics_hz >= " << s.min_physics_hz;
    std::cout << "\n";
    print_params(s.params, "plant_params");
  }
  return 0;
}

// "NAME=VALUE" with a number after the "=", or std::nullopt.
std::optional<std::pair<std::string, double>> parse_param(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0) return std::nullopt;
  try {
    std::size_t used = 0;
    const std::string value = text.substr(eq + 1);
    const double x = std::stod(value, &used);
    if (used != value.size()) return std::nullopt;
    return std::make_pair(text.substr(0, eq), x);
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

}  // namespace

Command add_laws_command(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("laws", "the agreement laws a scenario may name");
  return [cmd]() -> std::optional<int> {
    if (!*cmd) return std::nullopt;
    return list_laws();
  };
}

Command add_plants_command(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("plants", "the vehicles (plants) a scenario may fly");
  return [cmd]() -> std::optional<int> {
    if (!*cmd) return std::nullopt;
    return list_plants();
  };
}

Command add_check_law_command(CLI::App& app) {
  struct Options {
    std::string law;
    std::vector<std::string> params;
    std::string scenarios = in_repository("scenarios");
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "check-law", "fly a law through the promises a law may claim (the conformance kit)");
  cmd->add_option("law", o->law, "the law, as `swarm laws` names it")->required();
  cmd->add_option("--param", o->params, "NAME=VALUE: one of the law's parameters (repeatable)");
  cmd->add_option("--scenarios", o->scenarios,
                  "the repository's scenarios/ (paper/, faults_six, insider_seven)");
  return [cmd, o]() -> std::optional<int> {
    if (!*cmd) return std::nullopt;
    const LawSpec* spec = nullptr;
    try {
      spec = &find_law(o->law);
    } catch (const std::invalid_argument& e) {
      std::cerr << "swarm check-law: " << e.what() << "\n";
      return 2;
    }
    KitOptions k;
    k.scenarios = o->scenarios;
    for (const std::string& p : o->params) {
      const auto kv = parse_param(p);
      if (!kv) {
        std::cerr << "swarm check-law: --param '" << p << "': expected NAME=NUMBER\n";
        return 2;
      }
      if (!k.params.emplace(kv->first, kv->second).second) {
        std::cerr << "swarm check-law: --param '" << kv->first << "' given twice\n";
        return 2;
      }
    }
    try {
      resolve_law_params(*spec, k.params, "--param");
      const KitReport r = check_law(*spec, k);
      std::cout << r.table();
      std::cout << (r.passed() ? "kept every promise " + spec->name + " claims\n"
                               : "BROKE a promise " + spec->name + " claims\n");
      return r.passed() ? 0 : 1;
    } catch (const std::invalid_argument& e) {
      std::cerr << "swarm check-law: " << e.what() << "\n";
      return 2;
    } catch (const ScenarioError& e) {
      std::cerr << "swarm check-law: " << e.what() << "\n";
      return 2;
    } catch (const std::exception& e) {
      // Not the user's input: the law (or its LawSpec) is wrong.
      std::cerr << "swarm check-law: the law failed before its flights: " << e.what() << "\n";
      return 1;
    }
  };
}

}  // namespace qswarm
