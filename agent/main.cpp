// swarm-agent: one quadcopter (or particle) as its own process with its own DDS participant. The
// AgentLoop does the work; this file parses flags, sets up logging and wires signals.
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <cstdlib>

#include "agent/options.hpp"
#include "agent/stats.hpp"
#include "common/claim/claim_runner.hpp"
#include "common/record/run_dir.hpp"

namespace {
std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }
// However slow the rates, a stop request is seen within this many wall seconds.
constexpr double kMaxSleepS = 0.05;
}  // namespace

// How much nicer Fast DDS's threads run than the agent's tick (ParticipantOptions::threads_nice).
constexpr int kDdsThreadsNice = 15;

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
  if (!rc->transport.keystore.empty()) {
    // A replica that claims its id cannot hold a certificate for it in advance: it needs the
    // shared member identity of a compose keystore.
    if (claiming && !compose_keystore(rc->transport.keystore)) {
      std::fprintf(stderr,
                   "swarm-agent: --id auto: a replica that claims its id needs a compose keystore "
                   "(swarm keys SCENARIO --out DIR --compose), not one per agent (%s)\n",
                   rc->transport.keystore.c_str());
      return 2;
    }
    std::string why;
    identity = keystore_identity(rc->transport.keystore, "agent-" + std::to_string(id), why);
    if (identity.empty()) {
      std::fprintf(stderr, "swarm-agent: transport.keystore: %s\n", why.c_str());
      return 2;
    }
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, f.ignore_sigterm ? SIG_IGN : on_signal);
  // A hangup (the terminal gone, or the launcher gone while this process was stopped) stops it
  // cleanly too, with its stats written.
  std::signal(SIGHUP, on_signal);
  auto log = make_process_logger("agent", "");
  try {
    SteadyClock clock;
    DdsOptions dopt = dds_options(*rc, "swarm-agent", f.process);
    dopt.participant.identity = identity;
    if (!f.process.peer_hosts.empty()) {
      dopt.participant.unicast_peer_hosts =
          find_peer_hosts(f.process.peer_hosts, rc->agents.size() + 1, kPeerHostsWaitS, g_stop,
                          [&](const std::string& line) { log->info("{}", line); });
      if (g_stop) return 0;  // stopped while waiting for its peers: a stop, not a failure
      if (dopt.participant.unicast_peer_hosts.empty()) {
        say_peer_hosts_unresolved("swarm-agent", f.process.peer_hosts);
        return 2;
      }
    }
    // The tick is this process's deadline; hearing neighbours may wait (docs/benchmarks.md). Not
    // under DDS-Security: Fast DDS 2.9.1's handshakes race between its receive threads (see
    // ParticipantOptions::unicast_peers_first), and with them slowed a secure compose swarm
    // lost a pair of replicas that never heard each other.
    if (rc->transport.keystore.empty()) dopt.participant.threads_nice = kDdsThreadsNice;
    DdsParticipant participant(dopt.participant);
    // A replica claims its id before it reads or writes any state: the state reader then leaves
    // out its own samples from the start.
    std::optional<DdsClaimBus> claims;
    std::optional<IdClaimRunner> claim;
    if (claiming) {
      const std::set<AgentId> ids = rc->ids();
      claims.emplace(participant, rc->transport.run_id, claim_capacity(rc->agents.size()));
      claim.emplace(*claims, std::vector<AgentId>(ids.begin(), ids.end()), rc->transport.run_id, id,
                    IdClaimer::Config::for_swarm(rc->agents.size(), f.claim_timeout_s),
                    random_nonce(), clock);
      std::string why;
      const std::optional<AgentId> taken = claim->acquire(
          g_stop, why,
          [&](const std::string& line) { log->info("replica {:016x}: {}", claim->nonce(), line); });
      if (!taken) {
        log->error("replica {:016x}: no agent id: {}", claim->nonce(), why);
        return g_stop ? 0 : 2;  // stopped while claiming: a stop, not a failure
      }
      id = *taken;
    }
    dopt.state.self = id;
    DdsStateBus bus(participant, dopt.state, clock);
    const std::string name = "agent-" + std::to_string(id);
    const RunDir dir(f.run_dir);
    log = make_process_logger(name, dir.empty() ? "" : dir.agent_log(id).string());
    if (claim)
      log->info("replica {:016x} after {:.2f} s of claiming flies as agent {}", claim->nonce(),
                clock.now_s(), id);
    f.loop.time_scale = f.process.time_scale;
    f.loop.incarnation = clock.wall_ns();
    f.loop.tick_phase = tick_phase(rc->ids(), id);
    AgentLoop loop(*rc, id, f.loop, bus, clock);
    log->info("agent {} up: domain {}, {} law, time scale {}", id, rc->transport.domain_id,
              to_string(rc->agent.law.kind), f.process.time_scale);
    // Those it starts later run at the tick's: a reader's own multicast receive thread is started
    // by the thread that makes the reader.
    if (!participant.threads_priority().empty())
      log->info("Fast DDS's threads started with the participant run at {}",
                participant.threads_priority());
    int exit_code = 0;
    std::optional<ProcessUsage> flight_start;  // taken once, when the barrier releases it
    while (!g_stop) {
      const AgentLoop::Poll p = loop.poll();
      if (!flight_start && loop.running_since_s() >= 0.0) flight_start = process_usage();
      for (const auto& n : p.notes)
        log->log(n.warning ? spdlog::level::warn : spdlog::level::info, n.text);
      if (p.kill) {
        log->warn("t={:.3f} s: planned kill: SIGKILL to myself", loop.runtime().time_s());
        if (!dir.empty() && !dir.mark_planned_kill(id, loop.runtime().time_s()))
          log->error("cannot mark the planned kill in {}", dir.planned_kills(id).string());
        log->flush();
        std::raise(SIGKILL);
        std::_Exit(137);  // as PID 1 of a container the kernel ignores our own SIGKILL
      }
      if (p.done) break;
      if (claim) {
        if (const std::optional<std::string> why = claim->keep()) {
          log->error("replica {:016x} stops flying agent {}: {}", claim->nonce(), id, *why);
          exit_code = 2;
          break;
        }
      }
      clock.sleep_until(std::min(p.wake_at_s, clock.now_s() + kMaxSleepS));
    }
    loop.stop();
    log->info(final_report(loop, bus.counters()));
    if (!dir.empty() &&
        !write_stats(dir.agent_stats(id), loop, bus.counters(),
                     participant.writers().participants_known(), clock.now_s(), flight_start)) {
      log->error("cannot write {}", dir.agent_stats(id).string());
      exit_code = 3;  // the record is incomplete: say so, as the supervisor does
    }
    return exit_code;
  } catch (const std::exception& e) {
    log->error("fatal: {}", describe_exception(e));
    return 1;
  }
}
