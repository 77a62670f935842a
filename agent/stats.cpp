#include "agent/stats.hpp"

#include "common/dds/tick_transport.hpp"

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <iomanip>

namespace qswarm {

std::string final_report(const AgentLoop& loop, const BusCounters& c) {
  const AgentRuntime& a = loop.runtime();
  const Vec3 q = a.consensus(), x = a.position();
  char buf[512];
  std::snprintf(
      buf, sizeof buf,
      "stopping at t=%.3f s: consensus (%.6f, %.6f, %.6f) position (%.6f, %.6f, %.6f); "
      "published %llu, received %llu, dropped %llu, stale %llu, late ticks %llu of %llu "
      "(%llu physics steps); flows recovered at restart %d",
      a.time_s(), q.x(), q.y(), q.z(), x.x(), x.y(), x.z(),
      static_cast<unsigned long long>(c.published), static_cast<unsigned long long>(c.received),
      static_cast<unsigned long long>(c.dropped), static_cast<unsigned long long>(c.stale),
      static_cast<unsigned long long>(loop.overruns()),
      static_cast<unsigned long long>(loop.ticks()),
      static_cast<unsigned long long>(loop.physics_steps()), a.recovered_flows());
  return buf;
}

ProcessUsage process_usage() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  ProcessUsage u;
  u.cpu_s = static_cast<double>(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
            static_cast<double>(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec) * 1e-6;
  u.voluntary_switches = ru.ru_nvcsw;
  u.involuntary_switches = ru.ru_nivcsw;
  u.max_rss_kb = ru.ru_maxrss;
  u.epoch_s =
      std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  return u;
}

bool write_stats(const std::filesystem::path& path, const AgentLoop& loop, const BusCounters& c,
                 int participants_known, double wall_now_s,
                 const std::optional<ProcessUsage>& flight_start, const TickReceive* tick) {
  const ProcessUsage now = process_usage();
  const double since = loop.running_since_s();
  std::ofstream out(path);
  out << "cpu_s " << now.cpu_s << "\nwall_s " << (since >= 0 ? wall_now_s - since : 0.0)
      << "\nsteps " << loop.ticks() << "\nphysics_steps " << loop.physics_steps() << "\noverruns "
      << loop.overruns() << "\ndiscovery_s " << loop.lifecycle().discovery_s() << "\nmax_rss_kb "
      << now.max_rss_kb << "\nreceived " << c.received << "\ndropped " << c.dropped
      << "\ninterest_changes " << loop.interest_changes() << "\nparticipants " << participants_known
      << "\narrival_age_early " << c.ages.early << "\n";
  if (flight_start)
    out << "flight_cpu_s " << now.cpu_s - flight_start->cpu_s << "\nflight_voluntary_switches "
        << now.voluntary_switches - flight_start->voluntary_switches
        << "\nflight_involuntary_switches "
        << now.involuntary_switches - flight_start->involuntary_switches << "\nstarted_epoch_s "
        << std::fixed << std::setprecision(6) << flight_start->epoch_s << std::defaultfloat << "\n";
  if (tick != nullptr) {
    const TickReceive::Counters t = tick->counters();
    out << "tick_drains " << t.drains << "\ntick_datagrams " << t.datagrams << "\ntick_truncated "
        << t.truncated << "\n";
  }
  if (c.ages.total() > 0)
    out << "arrival_age_p50_ms " << c.ages.quantile_ms(0.5) << "\narrival_age_p99_ms "
        << c.ages.quantile_ms(0.99) << "\n";
  return static_cast<bool>(out.flush());
}

}  // namespace qswarm
