#include "common/runtime/run_load.hpp"

#include <google/protobuf/io/tokenizer.h>
#include <google/protobuf/text_format.h>
#include <sched.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "common/runtime/neighbourhood.hpp"
#include "common/transport/regular_file.hpp"

namespace qswarm {

namespace fs = std::filesystem;

namespace {

// A count a second as people read it: 78000, not 7.8e+04.
std::string per_s(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.0f", v);
  return buf;
}

class SilentErrors : public google::protobuf::io::ErrorCollector {
 public:
  void AddError(int, google::protobuf::io::ColumnNumber, const std::string&) override {}
  void AddWarning(int, google::protobuf::io::ColumnNumber, const std::string&) override {}
};

constexpr std::uintmax_t kMaxCalibrationBytes = std::uintmax_t{64} * 1024;

// Whether every cost is a finite, positive number of microseconds (a hand-edited or damaged file
// must not make a run look free, or impossible); the first field that is not, otherwise "".
std::string bad_cost(const plan::HostCalibration& c) {
  const std::pair<const char*, double> costs[] = {
      {"tick_us_particle", c.tick_us_particle()},
      {"tick_us_quadcopter", c.tick_us_quadcopter()},
      {"delivery_us_tick", c.delivery_us_tick()},
      {"delivery_us_threads", c.delivery_us_threads()},
      {"tick_us_particle_threads", c.tick_us_particle_threads()},
      {"tick_us_quadcopter_threads", c.tick_us_quadcopter_threads()},
  };
  for (const auto& [name, v] : costs) {
    if (!std::isfinite(v) || v <= 0.0 || v > 1e6) {
      std::ostringstream o;
      o << "field '" << name << "': " << v << " is not a cost in microseconds (0 to 1e6]";
      return o.str();
    }
  }
  if (c.quadcopter_steps_per_tick() == 0) return "field 'quadcopter_steps_per_tick': 0";
  return "";
}

}  // namespace

fs::path calibration_path() {
  if (const char* p = std::getenv("QSWARM_CALIBRATION"); p != nullptr && *p != '\0') return p;
  if (const char* s = std::getenv("XDG_STATE_HOME"); s != nullptr && *s != '\0')
    return fs::path(s) / "qswarm" / "calibration.txtpb";
  const char* home = std::getenv("HOME");
  return fs::path(home != nullptr && *home != '\0' ? home : ".") / ".local" / "state" / "qswarm" /
         "calibration.txtpb";
}

std::string host_name() {
  char buf[256] = {};
  if (gethostname(buf, sizeof buf - 1) != 0) return "unknown";
  return buf;
}

unsigned host_cores() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) > 0)
    return static_cast<unsigned>(CPU_COUNT(&set));
  const long n = sysconf(_SC_NPROCESSORS_ONLN);
  return n > 0 ? static_cast<unsigned>(n) : 1U;
}

std::optional<plan::HostCalibration> read_calibration(const fs::path& path, const std::string& host,
                                                      unsigned cores, std::string& why) {
  RegularFile f;
  const std::string text = read_regular_file(path, kMaxCalibrationBytes, f);
  if (f.problem == RegularFile::Problem::kMissing) {
    why = "none at " + path.string() + " (swarm calibrate measures this host)";
    return std::nullopt;
  }
  if (f.problem != RegularFile::Problem::kNone) {
    why = path.string() + ": " + f.why;
    return std::nullopt;
  }
  plan::HostCalibration c;
  google::protobuf::TextFormat::Parser parser;
  SilentErrors silent;  // a damaged file is said once, below, not logged by protobuf
  parser.RecordErrorsTo(&silent);
  if (!parser.ParseFromString(text, &c)) {
    why = path.string() + ": not a calibration (run swarm calibrate again)";
    return std::nullopt;
  }
  if (const std::string bad = bad_cost(c); !bad.empty()) {
    why = path.string() + ": " + bad + " (run swarm calibrate again)";
    return std::nullopt;
  }
  if (c.host() != host || c.cores() != cores) {
    why = path.string() + ": measured on " + c.host() + " with " + std::to_string(c.cores()) +
          " cores, not on this host (" + host + ", " + std::to_string(cores) +
          " cores): run swarm calibrate here";
    return std::nullopt;
  }
  why = path.string() + " (measured " + c.measured_at() + ")";
  return c;
}

plan::Load predict_load(const RunConfig& rc, double time_scale,
                        const std::optional<plan::HostCalibration>& cal, unsigned cores,
                        const std::string& calibration) {
  plan::Load load;
  const std::size_t n = rc.agents.size();
  load.set_agents(static_cast<std::uint32_t>(n));
  const double ticks_per_agent = rc.agent.consensus_hz * time_scale;
  load.set_ticks_per_s(ticks_per_agent * static_cast<double>(n));
  // Who hears whom at the start, pair by pair.
  const std::vector<Interest> interests = Neighbourhood::interests_at_start(rc);
  double heard = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      if (i != j &&
          Interest::hears(interests[i], interests[j], rc.agents[j].q0(), rc.agents[j].position_W))
        heard += 1.0;
    }
  }
  load.set_deliveries_per_tick(heard);
  load.set_deliveries_per_s(heard * ticks_per_agent);
  load.set_calibration(calibration);
  load.set_cores(cores);
  if (!cal) return load;

  const bool tick = rc.plan.tick_receive;
  const double particle = tick ? cal->tick_us_particle() : cal->tick_us_particle_threads();
  const double quad = tick ? cal->tick_us_quadcopter() : cal->tick_us_quadcopter_threads();
  // A quadcopter's tick is a point agent's plus its physics steps, measured at
  // quadcopter_steps_per_tick: the steps' cost a second follows the physics rate, not the
  // consensus rate. Any plant that is stepped is costed as the quadcopter (the one calibrated).
  const double step_us =
      rc.agent.plant_spec().follows_reference
          ? std::max(0.0, quad - particle) / static_cast<double>(cal->quadcopter_steps_per_tick())
          : 0.0;
  const double delivery_us = tick ? cal->delivery_us_tick() : cal->delivery_us_threads();
  const double agents = static_cast<double>(n);
  const double physics_cores = agents * rc.agent.physics_hz * time_scale * step_us * 1e-6;
  // Everything else is per tick: CPU a second per consensus hertz.
  const double per_hz_cores = (agents * particle + heard * delivery_us) * time_scale * 1e-6;
  const double ticks_cores = load.ticks_per_s() * particle * 1e-6 + physics_cores;
  const double predicted = physics_cores + per_hz_cores * rc.agent.consensus_hz;
  const double usable = kUsableCoreShare * cores;
  load.set_calibrated(true);
  load.set_usable_cores(usable);
  load.set_predicted_cores(predicted);
  load.set_sustained_deliveries_per_s(std::max(0.0, usable - ticks_cores) / (delivery_us * 1e-6));
  load.set_exceeds(predicted > usable);
  // Everything scales with the time scale; below swarm run's least (0.01) none holds.
  const double scale = predicted > 0 ? time_scale * usable / predicted : time_scale;
  load.set_holdable_time_scale(scale >= 0.01 ? scale : 0.0);
  // The fastest whole-hertz consensus rate that holds and that the physics rate divides (the
  // resolver refuses others), at least 1 Hz; 0 when none does (the physics alone is too much).
  double hz = rc.agent.consensus_hz;
  if (load.exceeds()) {
    const double most = per_hz_cores > 0 ? (usable - physics_cores) / per_hz_cores : 0.0;
    hz = 0.0;
    for (int steps = 1; most >= 1.0 && steps <= static_cast<int>(rc.agent.physics_hz); ++steps) {
      const double r = rc.agent.physics_hz / steps;
      if (r <= most && r >= 1.0 && r == std::floor(r)) {
        hz = r;
        break;
      }
    }
  }
  load.set_holdable_consensus_hz(hz);
  return load;
}

plan::Load predict_load_here(const RunConfig& rc, double time_scale) {
  const std::string host = host_name();
  const unsigned cores = host_cores();
  std::string why;
  const std::optional<plan::HostCalibration> cal =
      read_calibration(calibration_path(), host, cores, why);
  return predict_load(rc, time_scale, cal, cores, why);
}

namespace {

// What holds instead: a consensus rate (whole hertz, 0: none) and a time scale (0: none of at
// least swarm run's 0.01).
std::string what_holds(const plan::Load& l) {
  std::ostringstream o;
  o.precision(3);
  if (l.holdable_consensus_hz() > 0)
    o << "consensus_hz " << l.holdable_consensus_hz();
  else
    o << "no consensus rate of 1 Hz or more";
  o << ", or this rate at ";
  if (l.holdable_time_scale() > 0)
    o << "--time-scale " << l.holdable_time_scale();
  else
    o << "no --time-scale of 0.01 or more";
  return o.str();
}

}  // namespace

std::string describe_load(const plan::Load& l) {
  std::ostringstream o;
  o.precision(3);
  o << "load: " << l.agents() << " agents x "
    << (l.agents() > 0 ? l.ticks_per_s() / l.agents() : 0.0) << " ticks/s, each hearing "
    << (l.agents() > 0 ? l.deliveries_per_tick() / l.agents() : 0.0)
    << " agents at the start: " << per_s(l.deliveries_per_s()) << " samples received/s\n";
  if (!l.calibrated()) {
    o << "  host: not calibrated: " << l.calibration() << "\n";
    return o.str();
  }
  o << "  host: " << l.cores() << " cores, " << l.usable_cores()
    << " for agents; predicted agent CPU " << l.predicted_cores() << " cores; the host sustains "
    << per_s(l.sustained_deliveries_per_s()) << " samples/s beside these ticks (calibration "
    << l.calibration() << ")\n";
  if (l.exceeds())
    o << "  EXCEEDS this host: expect late ticks; real time holds at " << what_holds(l) << "\n";
  return o.str();
}

std::string load_warning(const plan::Load& l) {
  if (!l.calibrated() || !l.exceeds()) return "";
  std::ostringstream o;
  o.precision(3);
  o << "warning: predicted agent CPU " << l.predicted_cores() << " cores exceeds the "
    << l.usable_cores() << " this host sustains (" << per_s(l.deliveries_per_s())
    << " samples received/s): expect late ticks; real time holds at " << what_holds(l);
  return o.str();
}

std::optional<FittedCosts> fit_costs(const std::vector<CalibrationSample>& runs) {
  // Normal equations of the two-column least squares, in seconds per tick and per sample.
  double tt = 0, tr = 0, rr = 0, tc = 0, rc = 0;
  for (const CalibrationSample& s : runs) {
    if (!std::isfinite(s.cpu_s) || !std::isfinite(s.ticks) || !std::isfinite(s.received))
      return std::nullopt;
    tt += s.ticks * s.ticks;
    tr += s.ticks * s.received;
    rr += s.received * s.received;
    tc += s.ticks * s.cpu_s;
    rc += s.received * s.cpu_s;
  }
  const double det = tt * rr - tr * tr;
  // Runs whose samples per tick are (nearly) the same cannot tell the two costs apart.
  if (!(det > 1e-9 * tt * rr)) return std::nullopt;
  FittedCosts f;
  f.tick_us = (tc * rr - rc * tr) / det * 1e6;
  f.delivery_us = (rc * tt - tc * tr) / det * 1e6;
  if (!(f.tick_us > 0) || !(f.delivery_us > 0)) return std::nullopt;
  return f;
}

}  // namespace qswarm
