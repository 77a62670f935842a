// `swarm keys SCENARIO --out DIR [--days N] [--compose]`: a DDS-Security keystore for the
// scenario's agents and supervisor (Keystore::write).
#include <CLI/CLI.hpp>

#include <iostream>
#include <memory>
#include <string>

#include "common/scenario/scenario.hpp"
#include "common/security/keystore.hpp"
#include "launcher/commands.hpp"

namespace qswarm {

Command add_keys_command(CLI::App& app) {
  struct Options {
    std::string scenario, out;
    int days = 365, agents = -1;
    bool compose = false;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd =
      app.add_subcommand("keys", "a DDS-Security keystore for a scenario's agents and supervisor");
  cmd->add_option("scenario", o->scenario, "scenario file")->required();
  cmd->add_option("--out", o->out, "new keystore directory")->required();
  cmd->add_option("--days", o->days, "validity in days (default 365)")->check(CLI::Range(1, 36500));
  cmd->add_option("--agents", o->agents,
                  "for N seeded random agents (ids 1..N), as swarm run and swarm deploy --agents "
                  "fly them, instead of the scenario's list")
      ->check(CLI::Range(1, static_cast<int>(kMaxSwarmAgents)));
  cmd->add_flag("--compose", o->compose,
                "one member identity for compose replicas (they claim their ids) instead of one "
                "per agent");
  return [cmd, o]() -> std::optional<int> {
    if (!*cmd) return std::nullopt;
    try {
      ScenarioOverrides ov;
      ov.agents = o->agents;
      const RunConfig rc = load_scenario(o->scenario, ov);
      std::vector<AgentId> ids;
      for (const AgentSpec& a : rc.agents) ids.push_back(a.id);
      Keystore::write(o->out, ids, o->days, o->compose);
      if (o->compose)
        std::cout << "swarm keys: compose keystore (a member identity and the supervisor) in "
                  << o->out << "\n";
      else
        std::cout << "swarm keys: keystore for " << ids.size() << " agents and the supervisor in "
                  << o->out << "\n";
      return 0;
    } catch (const ScenarioError& e) {
      std::cerr << "swarm keys: " << e.what() << "\n";
    } catch (const KeystoreError& e) {
      std::cerr << "swarm keys: " << e.what() << "\n";
    }
    return 2;
  };
}

}  // namespace qswarm
