#include "agent/flight.hpp"

#include <algorithm>
#include <csignal>
#include <cstdlib>

#include "agent/stats.hpp"
#include "common/app/process_dds.hpp"
#include "common/app/process_life.hpp"
#include "common/record/run_dir.hpp"

namespace qswarm {

namespace {
// However slow the rates, a stop request is seen within this many wall seconds.
constexpr double kMaxSleepS = 0.05;
}  // namespace

std::optional<AgentId> claim_id(DdsBus& bus, const RunConfig& rc, const AgentFlags& f,
                                AgentId fixed, Clock& clock, const std::atomic<bool>& stop,
                                spdlog::logger& log, std::optional<IdClaimRunner>& runner,
                                int& exit_code) {
  const std::set<AgentId> ids = rc.ids();
  const double timeout_s = f.claim_timeout_s >= 0.0 ? f.claim_timeout_s : rc.plan.claim_timeout_s;
  runner.emplace(bus.claim_bus(), std::vector<AgentId>(ids.begin(), ids.end()), rc.transport.run_id,
                 fixed, IdClaimer::Config::with_period(rc.plan.claim_period_s, timeout_s),
                 random_nonce(), clock);
  std::string why;
  const std::optional<AgentId> taken = runner->acquire(stop, why, [&](const std::string& line) {
    log.info("replica {:016x}: {}", runner->nonce(), line);
  });
  if (!taken) {
    log.error("replica {:016x}: no agent id: {}", runner->nonce(), why);
    exit_code = stop ? 0 : 2;  // stopped while claiming: a stop, not a failure
  }
  return taken;
}

int fly(const RunConfig& rc, AgentId id, AgentFlags& f, DdsBus& bus, Clock& clock,
        std::optional<IdClaimRunner>& claim, const std::atomic<bool>& stop) {
  const RunDir dir(f.run_dir);
  auto log = make_process_logger("agent-" + std::to_string(id),
                                 dir.empty() ? "" : dir.agent_log(id).string());
  if (claim)
    log->info("replica {:016x} after {:.2f} s of claiming flies as agent {}", claim->nonce(),
              clock.now_s(), id);
  f.loop.time_scale = f.process.time_scale;
  f.loop.incarnation = clock.wall_ns();
  f.loop.tick_phase = rc.plan.tick_phase(rc.ids(), id);
  f.loop.host = host_label(rc.plan.hosts.interface);
  AgentLoop loop(rc, id, f.loop, bus, clock);
  log->info("agent {} up: domain {}, {} law, time scale {}", id, rc.transport.domain_id,
            rc.agent.law.law, f.process.time_scale);
  // Those it starts later run at the tick's: a reader's own multicast receive thread is started
  // by the thread that makes the reader.
  if (!bus.participant().threads_priority().empty())
    log->info("Fast DDS's threads started with the participant run at {}",
              bus.participant().threads_priority());
  int exit_code = 0;
  std::optional<ProcessUsage> flight_start;  // taken once, when the barrier releases it
  while (!stop) {
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
  if (!dir.empty() && !write_stats(dir.agent_stats(id), loop, bus.counters(),
                                   bus.participant().writers().participants_known(), clock.now_s(),
                                   flight_start, bus.participant().tick_receive())) {
    log->error("cannot write {}", dir.agent_stats(id).string());
    exit_code = 3;  // the record is incomplete: say so, as the supervisor does
  }
  return exit_code;
}

}  // namespace qswarm
