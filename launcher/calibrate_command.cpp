// `swarm calibrate`: measure what this host sustains (agent CPU per tick and per neighbour sample
// received) by flying short all-to-all swarms of real agent processes, and keep it where `swarm
// inspect` and `swarm run` read it (run_load.hpp).
#include <google/protobuf/text_format.h>
#include <CLI/CLI.hpp>

#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <thread>

#include "common/app/cli_checks.hpp"
#include "common/record/run_dir.hpp"
#include "common/runtime/run_load.hpp"
#include "common/transport/port_plan.hpp"
#include "launcher/commands.hpp"
#include "launcher/process_group.hpp"

namespace qswarm {

namespace fs = std::filesystem;

namespace {

std::atomic<int> g_calibrate_signal{0};
void on_calibrate_signal(int sig) { g_calibrate_signal = sig; }

struct CalibrateOptions {
  std::string out;  // default calibration_path()
  double seconds = 8.0;
  int domain = 0;
  std::string keep;  // keep the calibration runs here
};

// One calibration run: n agents that all hear each other for `seconds` (never agreeing, so they
// fly the whole time), at 50 Hz.
struct Flight {
  const char* name;
  int agents;
  bool quadcopter;
  bool tick;
};

std::string scenario_text(const Flight& f, double seconds) {
  std::ostringstream o;
  o << "name: \"calibrate-" << f.name << "\"\n"
    << "random_agents { count: " << f.agents << " box_m: 30 }\n"
    << "mode: " << (f.quadcopter ? "QUADCOPTER" : "PARTICLE") << "\n"
    << "law: EDGE_FLOW\nweight { policy: UNWEIGHTED }\n"
    << "topology { policy: STICKY_PROXIMITY threshold_m: 100 }\n"
    << "rates { consensus_hz: 50 }\n"
    << "convergence { tolerance_m: 1e-12 hold_s: 1000 }\n"
    << "transport { delivery: ALL multicast: false receive: " << (f.tick ? "TICK" : "THREADS")
    << " }\n"
    << "duration_s: " << seconds << "\nseed: 1\n";
  return o.str();
}

// The agents' summed flight CPU, ticks and samples received, from their agent-N.stats.
std::optional<CalibrationSample> read_sample(const RunDir& dir, int agents, std::string& why) {
  CalibrationSample s;
  for (int id = 1; id <= agents; ++id) {
    std::ifstream in(dir.agent_stats(static_cast<AgentId>(id)));
    std::string key;
    double v = 0;
    bool cpu = false, steps = false, received = false;
    while (in >> key >> v) {
      if (key == "flight_cpu_s") s.cpu_s += v, cpu = true;
      if (key == "steps") s.ticks += v, steps = true;
      if (key == "received") s.received += v, received = true;
    }
    if (!cpu || !steps || !received) {
      why = "agent " + std::to_string(id) + " of " + dir.str() + " wrote no complete stats";
      return std::nullopt;
    }
  }
  return s;
}

// Flies one calibration run with `swarm run`; its sample, or nothing (and why) if it did not fly
// to its end or was interrupted.
std::optional<CalibrationSample> fly(const Flight& f, const CalibrateOptions& opt,
                                     const fs::path& root, std::string& why) {
  const fs::path scenario = root / (std::string(f.name) + ".txtpb");
  const fs::path out = root / f.name;
  if (!write_whole(scenario, scenario_text(f, opt.seconds))) {
    why = "cannot write " + scenario.string() + " (disk full?)";
    return std::nullopt;
  }
  ProcessGroup procs;
  procs.spawn("calibration", 0,
              {(bin_dir() / "swarm").string(), "run", scenario.string(), "--out", out.string(),
               "--quiet", "--domain", std::to_string(opt.domain)},
              (root / (std::string(f.name) + ".out")).string(), false);
  while (procs.any_running()) {
    if (g_calibrate_signal != 0) {
      procs.terminate_all(10.0);
      why = "interrupted";
      return std::nullopt;
    }
    procs.reap();
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  if (g_calibrate_signal != 0) {  // came as the run ended: still not a calibration
    why = "interrupted";
    return std::nullopt;
  }
  const int status = procs.children().front().status;
  // Exit 1: it flew its whole duration without agreeing, as it was made to.
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 1) {
    why = std::string("the ") + f.name + " run " + describe_status(status) + " (see " +
          (root / (std::string(f.name) + ".out")).string() + ")";
    return std::nullopt;
  }
  return read_sample(RunDir(out), f.agents, why);
}

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

int calibrate(const CalibrateOptions& opt) {
  const fs::path path = opt.out.empty() ? calibration_path() : fs::path(opt.out);
  std::error_code ec;
  // Where it is kept is checked before a minute of flying: replaced whole at the end, it must be
  // a regular file or nothing yet (a FIFO or /dev/zero would be replaced, not written), in a
  // directory that can be made.
  const fs::file_status at = fs::symlink_status(path, ec);
  fs::create_directories(path.parent_path().empty() ? "." : path.parent_path(), ec);
  if ((fs::exists(at) && !fs::is_regular_file(at)) || ec) {
    std::cerr << "swarm calibrate: " << (opt.out.empty() ? "QSWARM_CALIBRATION" : "--out") << " "
              << path.string() << ": expected a regular file, or none yet, in a directory that "
              << "can be made" << (ec ? " (" + ec.message() + ")" : std::string()) << "\n";
    return 2;
  }
  fs::path root;
  if (!opt.keep.empty()) {
    root = opt.keep;
    fs::create_directories(root, ec);
    if (ec || !fs::is_directory(root, ec) || !fs::is_empty(root, ec) || ec) {
      std::cerr << "swarm calibrate: --keep " << opt.keep
                << ": expected a new or empty directory\n";
      return 2;
    }
  } else {
    const fs::path tmp = fs::temp_directory_path(ec);
    std::string tmpl = (tmp / "qswarm-calibrate-XXXXXX").string();
    if (ec || mkdtemp(tmpl.data()) == nullptr) {
      const char* env = std::getenv("TMPDIR");
      std::cerr << "swarm calibrate: cannot make a directory for its runs under "
                << (ec ? std::string(env != nullptr ? env : "/tmp") : tmp.string())
                << " (TMPDIR); give one that exists and is writable, or --keep DIR\n";
      return 2;
    }
    root = tmpl;
  }
  std::signal(SIGINT, on_calibrate_signal);
  std::signal(SIGTERM, on_calibrate_signal);
  const Flight flights[] = {
      {"particle4-tick", 4, false, true},       {"particle24-tick", 24, false, true},
      {"quadcopter4-tick", 4, true, true},      {"particle4-threads", 4, false, false},
      {"particle24-threads", 24, false, false}, {"quadcopter4-threads", 4, true, false}};
  std::vector<CalibrationSample> samples;
  int code = 0;
  std::string why;
  for (const Flight& f : flights) {
    std::cout << "swarm calibrate: flying " << f.agents << " "
              << (f.quadcopter ? "quadcopters" : "point agents") << " all-to-all for "
              << opt.seconds << " s, receiving " << (f.tick ? "at the tick" : "on threads")
              << std::endl;
    const std::optional<CalibrationSample> s = fly(f, opt, root, why);
    if (!s) {
      code = g_calibrate_signal != 0 ? 128 + g_calibrate_signal : 1;
      break;
    }
    samples.push_back(*s);
  }
  plan::HostCalibration c;
  if (code == 0) {
    // Per receive mode: the two point-agent runs give CPU per tick and per sample; the
    // quadcopters' run, with that per-sample cost, its CPU per tick.
    for (int mode = 0; mode < 2 && code == 0; ++mode) {
      const CalibrationSample* r = &samples[static_cast<std::size_t>(mode) * 3];
      const std::optional<FittedCosts> fit = fit_costs({r[0], r[1]});
      const double quad =
          fit ? (r[2].cpu_s - r[2].received * fit->delivery_us * 1e-6) / r[2].ticks * 1e6 : 0.0;
      if (!fit || !(quad > 0) || !std::isfinite(quad)) {
        why = std::string("the runs ") + (mode == 0 ? "at the tick" : "on threads") +
              " do not tell CPU per tick from CPU per sample (a busy host? try again, or "
              "--seconds longer)";
        code = 1;
        break;
      }
      if (mode == 0) {
        c.set_tick_us_particle(fit->tick_us);
        c.set_delivery_us_tick(fit->delivery_us);
        c.set_tick_us_quadcopter(quad);
      } else {
        c.set_tick_us_particle_threads(fit->tick_us);
        c.set_delivery_us_threads(fit->delivery_us);
        c.set_tick_us_quadcopter_threads(quad);
      }
    }
  }
  if (opt.keep.empty()) fs::remove_all(root, ec);
  if (code == 0 && g_calibrate_signal != 0) {  // a signal during the fit: nothing is kept
    code = 128 + g_calibrate_signal;
    why = "interrupted";
  }
  if (code != 0) {
    std::cerr << "swarm calibrate: " << why << "; nothing written\n";
    return code;
  }
  c.set_host(host_name());
  c.set_cores(host_cores());
  c.set_measured_at(utc_now());
  c.set_seconds_per_run(opt.seconds);
  c.set_quadcopter_steps_per_tick(10);  // the default rates: 500 Hz physics, 50 Hz consensus
  std::string text;
  google::protobuf::TextFormat::PrintToString(c, &text);
  if (!write_whole(path, "# swarm calibrate: what this host sustains (run_load.hpp)\n" + text)) {
    std::cerr << "swarm calibrate: cannot write " << path.string() << " (disk full?)\n";
    return 3;
  }
  std::cout << "swarm calibrate: " << c.host() << ", " << c.cores() << " cores; agent CPU per tick "
            << c.tick_us_particle() << " us (point agent), " << c.tick_us_quadcopter()
            << " us (quadcopter), per sample received " << c.delivery_us_tick()
            << " us at the tick; on threads " << c.tick_us_particle_threads() << ", "
            << c.tick_us_quadcopter_threads() << ", " << c.delivery_us_threads()
            << " us\nswarm calibrate: written to " << path.string() << "\n";
  return 0;
}

}  // namespace

Command add_calibrate_command(CLI::App& app) {
  auto o = std::make_shared<CalibrateOptions>();
  CLI::App* cmd = app.add_subcommand(
      "calibrate", "measure what this host sustains, for swarm inspect and swarm run");
  cmd->add_option("--out", o->out,
                  "where to keep it (default: " + calibration_path().string() +
                      "; QSWARM_CALIBRATION overrides)");
  cmd->add_option("--seconds", o->seconds, "wall seconds each of the six runs flies (default 8)")
      ->check(finite_range(2.0, 600.0));
  cmd->add_option("--domain", o->domain, "DDS domain id of its runs (default 0)")
      ->check(CLI::Range(0, static_cast<int>(PortPlan::kMaxDomain)));
  cmd->add_option("--keep", o->keep, "keep the runs' directories in this new directory");
  return [cmd, o]() -> std::optional<int> {
    if (!*cmd) return std::nullopt;
    return calibrate(*o);
  };
}

}  // namespace qswarm
