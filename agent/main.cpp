// swarm-agent: one quadcopter (or particle) as its own process with its own DDS participant. The
// AgentLoop does the work (agent/flight.cpp); this file parses flags, wires the DDS side and
// signals.
#include <CLI/CLI.hpp>

#include <atomic>
#include <csignal>
#include <cstdio>

#include "agent/flight.hpp"
#include "common/app/process_dds.hpp"
#include "common/app/process_life.hpp"
#include "common/dds/tick_transport.hpp"
#include "common/security/keystore.hpp"

namespace {
std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }
}  // namespace

int main(int argc, char** argv) {
  using namespace qswarm;
  exit_cleanly_on_uncaught_exceptions("swarm-agent");
  CLI::App app{"swarm-agent: one quadcopter of the swarm, over DDS"};
  AgentFlags f;
  add_agent_options(app, f);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  const std::optional<RunConfig> rc = load_for_process("swarm-agent", f.process);
  if (!rc) return 2;
  const bool claiming = f.claim || f.id == "auto";
  AgentId id = f.id == "auto" ? 0 : static_cast<AgentId>(std::stoul(f.id));
  if (id != 0 && !rc->spec(id)) {
    std::fprintf(stderr, "swarm-agent: --id %u: expected the id of an agent listed in %s\n", id,
                 f.process.scenario.c_str());
    return 2;
  }
  std::string identity;
  try {
    if (!rc->transport.keystore.empty())
      identity = Keystore(rc->transport.keystore).identity_of_agent(id, claiming);
  } catch (const KeystoreError& e) {
    std::fprintf(stderr, "swarm-agent: transport.keystore: %s\n", e.what());
    return 2;
  }
  if (!keystore_ready("swarm-agent", *rc, identity)) return 2;
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, f.ignore_sigterm ? SIG_IGN : on_signal);
  // A hangup (the terminal gone, or the launcher gone while this process was stopped) stops it
  // cleanly too, with its stats written.
  std::signal(SIGHUP, on_signal);
  auto log = make_process_logger("agent", "");
  try {
    ProcessDds d =
        process_dds("swarm-agent", *rc, f.process, "swarm-agent", identity, g_stop,
                    StoppedWaiting::kExit, [&](const std::string& line) { log->info("{}", line); });
    if (d.exit_code >= 0) return d.exit_code;
    d.options.participant.threads_nice = rc->plan.dds_threads_nice;
    d.options.state.self = id;
    d.options.id_claims = d.options.claim_first = claiming;  // the state waits for its id
    d.options.participant.tick_receive = rc->plan.tick_receive;
    DrainingClock clock;
    DdsBus bus(d.options, clock);
    clock.drain(bus.participant().tick_receive());
    std::optional<IdClaimRunner> claim;
    if (claiming) {
      int exit_code = 0;
      const std::optional<AgentId> taken =
          claim_id(bus, *rc, f, id, clock, g_stop, *log, claim, exit_code);
      if (!taken) return exit_code;
      id = *taken;
      bus.fly_as(id);
    }
    return fly(*rc, id, f, bus, clock, claim, g_stop);
  } catch (const std::exception& e) {
    log->error("fatal: {}", describe_exception(e));
    return 1;
  }
}
