// swarm-preview: flies a scenario's agreement in one process with the bare per-agent laws in
// lockstep (LockstepLaws: the same law objects the agent processes run, every agent stepping at
// every tick from the others' states of the previous tick; no DDS, dynamics or faults), and prints
// where the agents met. Without a SCENARIO it flies scenarios/demo.txtpb, the paper's time-varying
// weighted rendezvous (section 2.7.2), and compares with the paper's point.
//
// usage: swarm-preview [SCENARIO] [--law L] [--duration S] [--csv FILE] [--liar ID:KIND[:X,Y,Z]]
// Exit status: 0 when the agents' mean is within 1e-6 m of the reference (the paper's point for
// the demo, the initial average for a SCENARIO), or with --liar when the honest agents met inside
// their initial bounding box; 1 when not; 2 for bad input (a flag, or a scenario field, named); 3
// when the CSV could not be written completely.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <optional>
#include <string>

#include "common/core/graph.hpp"
#include "common/scenario/scenario.hpp"
#include "common/sim/liar.hpp"
#include "common/sim/lockstep_laws.hpp"

namespace fs = std::filesystem;
using namespace qswarm;

namespace {

constexpr char kUsage[] =
    "usage: swarm-preview [SCENARIO] [--law L] [--duration S] [--csv FILE] [--liar "
    "ID:KIND[:X,Y,Z]]\n"
    "  SCENARIO       a scenario file (default scenarios/demo.txtpb, the paper's time-varying\n"
    "                 rendezvous, from the current directory or the build tree)\n"
    "  --law L        the agreement law, any `swarm laws` lists (overrides the scenario's)\n"
    "  --duration S   simulated seconds before giving up (overrides the scenario's duration_s);\n"
    "                 the flight ends earlier once the disagreement is below the scenario's\n"
    "                 convergence.tolerance_m\n"
    "  --csv FILE     every agent's consensus state at every tick: t_s,id,qx,qy,qz (with --liar,\n"
    "                 every honest agent's)\n"
    "  --liar ID:KIND[:X,Y,Z]  agent ID lies to its neighbours every tick, running no law: KIND\n"
    "                 constant (claims X,Y,Z, default 1000,1000,1000), drift (its start plus "
    "X,Y,Z\n"
    "                 m/s times t, default 0.5,0.5,0.5) or split (+X,Y,Z to even ids, minus to "
    "odd\n"
    "                 ones). The flight lasts the whole duration; it succeeds when the honest "
    "agents\n"
    "                 meet inside their initial bounding box\n";

// Paper, section 2.7.2: the time-varying rendezvous meets at q* = (15.25, 10.25, 31).
const Vec3 kPaperPoint(15.25, 10.25, 31.0);
constexpr double kMeanTolerance_m = 1e-6;

struct Options {
  std::string scenario;  // empty: the demo
  ScenarioOverrides overrides;
  std::string csv;
  std::optional<Liar> liar;
};

// What the preview flies, from the run as a scenario resolves it. RunConfig's fields are read here
// and nowhere else in this file.
struct Flight {
  std::string title;
  LockstepConfig lockstep;
  double duration_s = 0.0;
  double tolerance_m = 0.0;
};

Flight plan_flight(const RunConfig& rc) {
  Flight f;
  const std::string& about = rc.resolved.description();
  f.title = about.empty() ? rc.name : rc.name + ": " + about;
  for (const AgentSpec& a : rc.agents) f.lockstep.agents.push_back({a.id, a.q0()});
  f.lockstep.law = rc.agent.law;
  f.lockstep.consensus_rate_hz = rc.agent.consensus_hz;
  f.duration_s = rc.judge.duration_s;
  f.tolerance_m = rc.judge.tolerance_m;
  return f;
}

// scenarios/demo.txtpb from the current directory (the repository root), else the copy the build
// keeps in the build tree (bin/../scenarios/).
std::string find_demo() {
  const fs::path rel = fs::path("scenarios") / "demo.txtpb";
  if (fs::is_regular_file(rel)) return rel.string();
  std::error_code ec;
  const fs::path build_tree = fs::read_symlink("/proc/self/exe", ec).parent_path().parent_path();
  if (!ec && fs::is_regular_file(build_tree / rel)) return (build_tree / rel).string();
  throw ScenarioError(
      "no SCENARIO given and scenarios/demo.txtpb is neither in the current directory nor in the "
      "build tree");
}

double parse_seconds(const std::string& flag, const std::string& text) {
  std::size_t used = 0;
  double v = 0.0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || !std::isfinite(v) || v <= 0.0) {
    throw ScenarioError(flag + ": expected simulated seconds > 0, got '" + text + "'");
  }
  return v;
}

// Returns the exit status when the command line ends the program (--help, bad input).
std::optional<int> parse(int argc, char** argv, Options& opt) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--help" || a == "-h") {
      std::printf("%s", kUsage);
      return 0;
    }
    if ((a == "--law" || a == "--duration" || a == "--csv" || a == "--liar") && !has_value) {
      std::fprintf(stderr, "swarm-preview: %s needs a value (try --help)\n", a.c_str());
      return 2;
    }
    if (a == "--law") {
      opt.overrides.law = argv[++i];
      if (opt.overrides.law.empty()) {
        std::fprintf(stderr, "swarm-preview: --law: an empty law name (swarm laws lists them)\n");
        return 2;
      }
    } else if (a == "--duration") {
      opt.overrides.duration_s = parse_seconds(a, argv[++i]);
    } else if (a == "--csv") {
      opt.csv = argv[++i];
    } else if (a == "--liar") {
      try {
        opt.liar = parse_liar(argv[++i]);
      } catch (const std::invalid_argument& e) {
        throw ScenarioError(std::string("--liar: ") + e.what());
      }
    } else if (a.starts_with("-") || !opt.scenario.empty()) {
      std::fprintf(stderr, "swarm-preview: unknown argument '%s' (try --help)\n", a.c_str());
      return 2;
    } else {
      opt.scenario = a;
    }
  }
  return std::nullopt;
}

void write_states(std::ofstream& csv, const LockstepLaws& swarm) {
  const Positions q = swarm.states();
  for (int i = 0; i < swarm.size(); ++i) {
    if (swarm.is_liar(i)) continue;  // what it claims is not a state: the honest ones are
    csv << swarm.time_s() << ',' << swarm.law(i).id() << ',' << q[i].x() << ',' << q[i].y() << ','
        << q[i].z() << '\n';
  }
}

// With a liar every measure is of the honest agents: a liar's claim is not a state.
struct Measure {
  double disagreement_m = 0.0;
  double outside_m = 0.0;  // farthest honest agent outside the honest initial bounding box
};
Measure measure(const LockstepLaws& swarm) {
  const Positions q = swarm.honest_states();
  return {disagreement(q), outside_box_m(q, swarm.honest_initial_states())};
}

void print_agents(const LockstepLaws& swarm) {
  if (swarm.size() > 16) {
    std::printf("  (%d agents, not listed)\n", swarm.size());
    return;
  }
  const Positions q = swarm.states();
  for (int i = 0; i < swarm.size(); ++i) {
    std::printf("  agent %u at (%.4f, %.4f, %.4f)%s\n", static_cast<unsigned>(swarm.law(i).id()),
                q[i].x(), q[i].y(), q[i].z(),
                swarm.is_liar(i) ? " (the liar's own law, which nobody heard)" : "");
  }
}

// The verdict under a liar: did the honest agents meet inside their initial box? 0 yes, 1 no.
int judge_honest(const LockstepLaws& swarm, const Liar& liar, double tolerance_m) {
  const Measure m = measure(swarm);
  const Vec3 mean = average(swarm.honest_states());
  std::printf("agent %u lied (%s) for %.2f s\nhonest mean (%.6f, %.6f, %.6f)\n",
              static_cast<unsigned>(liar.id), to_string(liar.kind).c_str(), swarm.time_s(),
              mean.x(), mean.y(), mean.z());
  std::printf(
      "honest disagreement %.3e m, farthest honest agent %.3e m outside the honest initial "
      "bounding box\n",
      m.disagreement_m, m.outside_m);
  const bool met = m.disagreement_m < tolerance_m && m.outside_m < tolerance_m;
  std::printf("%s\n", met ? "the honest agents met inside their initial bounding box"
                          : "the liar kept the honest agents apart or dragged them out of their "
                            "initial bounding box");
  return met ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  RunConfig rc;
  bool demo = false;
  try {
    if (const std::optional<int> done = parse(argc, argv, opt)) return *done;
    demo = opt.scenario.empty();
    rc = load_scenario(demo ? find_demo() : opt.scenario, opt.overrides);
    if (opt.liar && !rc.spec(opt.liar->id))
      throw ScenarioError("--liar: agent " + std::to_string(opt.liar->id) +
                          " is not one of the scenario's agents");
  } catch (const ScenarioError& e) {
    std::fprintf(stderr, "swarm-preview: %s\n", e.what());
    return 2;
  }
  Flight flight = plan_flight(rc);
  flight.lockstep.liar = opt.liar;
  if (flight.lockstep.law.topology.policy == TopologyPolicy::kRange) {
    // Under RANGE the agents link by their physical distance, which the bare laws do not have.
    std::fprintf(stderr,
                 "swarm-preview: scenario field 'topology.policy': expected FIXED, PROXIMITY or "
                 "STICKY_PROXIMITY (RANGE links follow physical positions, which the bare laws in "
                 "lockstep do not fly), got RANGE\n");
    return 2;
  }
  LockstepLaws swarm(flight.lockstep);
  std::ofstream csv;
  if (!opt.csv.empty()) {
    // A new file, a regular one to write over, or a character device (/dev/null): a FIFO would
    // block the preview until someone reads it, and a directory or a socket is no file of states.
    std::error_code ec;
    const std::filesystem::file_status st = std::filesystem::status(opt.csv, ec);
    if (std::filesystem::exists(st) && !std::filesystem::is_regular_file(st) &&
        !std::filesystem::is_character_file(st)) {
      std::fprintf(stderr, "swarm-preview: --csv %s: not a file to write states into\n",
                   opt.csv.c_str());
      return 2;
    }
    if (ec && ec != std::errc::no_such_file_or_directory) {
      std::fprintf(stderr, "swarm-preview: --csv %s: %s\n", opt.csv.c_str(), ec.message().c_str());
      return 2;
    }
    csv.open(opt.csv);
    if (!csv) {
      std::fprintf(stderr, "swarm-preview: --csv: cannot write %s\n", opt.csv.c_str());
      return 2;
    }
    csv << std::setprecision(17) << "t_s,id,qx,qy,qz\n";  // 17 digits: every double exactly
  }

  const LawConfig& law = flight.lockstep.law;
  const bool liar = opt.liar.has_value();
  std::printf("%s\n", flight.title.c_str());
  std::printf("%d agents, %s law, %g Hz, %s weights, %s topology", swarm.size(), law.law.c_str(),
              flight.lockstep.consensus_rate_hz, to_string(law.weight.policy).c_str(),
              to_string(law.topology.policy).c_str());
  if (law.topology.policy != TopologyPolicy::kFixed) {
    std::printf(" (threshold %g m)", law.topology.threshold_m);
  }
  std::printf(", gain %g\nthe bare laws in lockstep: no DDS, dynamics or faults\n", law.gain);
  if (liar) {
    std::printf("%8s %6s %10s %14s %14s\n", "t [s]", "edges", "lambda2", "honest dis [m]",
                "outside [m]");
  } else {
    std::printf("%8s %6s %10s %14s\n", "t [s]", "edges", "lambda2", "disagree [m]");
  }
  // A row at the start, every 5 s and whenever the graph changes.
  double next_print = 0.0;
  std::size_t edges_before = swarm.edges().size();
  const Vec3 initial_average = average(swarm.initial_states());
  for (;;) {
    if (csv.is_open()) write_states(csv, swarm);
    const auto edges = swarm.edges();
    const bool periodic = swarm.time_s() >= next_print;
    if (periodic || edges.size() != edges_before) {
      const Spectrum s = analyze(laplacian(swarm.size(), edges));
      if (liar) {
        const Measure m = measure(swarm);
        std::printf("%8.2f %6zu %10.4f %14.6g %14.6g\n", swarm.time_s(), edges.size(), s.lambda2,
                    m.disagreement_m, m.outside_m);
      } else {
        std::printf("%8.2f %6zu %10.4f %14.6f\n", swarm.time_s(), edges.size(), s.lambda2,
                    disagreement(swarm.states()));
      }
      if (periodic) next_print += 5.0;
      edges_before = edges.size();
    }
    // A liar can drag agents that already agree: its flight lasts the whole duration.
    if (swarm.time_s() >= flight.duration_s ||
        (!liar && disagreement(swarm.states()) < flight.tolerance_m)) {
      break;
    }
    swarm.step();
  }
  int status = 0;
  if (liar) {
    std::printf("\n");
    print_agents(swarm);
    status = judge_honest(swarm, *opt.liar, flight.tolerance_m);
  } else {
    const double left_m = disagreement(swarm.states());
    std::printf("\n%s after %.2f s (disagreement %.2e m, tolerance %g m)\n",
                left_m < flight.tolerance_m ? "met" : "not met", swarm.time_s(), left_m,
                flight.tolerance_m);
    print_agents(swarm);
    const Vec3 met = average(swarm.states());
    const Vec3 reference = demo ? kPaperPoint : initial_average;
    const char* label = demo ? "paper q* " : "initial average";
    std::printf("mean     (%.6f, %.6f, %.6f)\n%s (%.6f, %.6f, %.6f)\n|mean - %s| = %.3e m\n",
                met.x(), met.y(), met.z(), label, reference.x(), reference.y(), reference.z(),
                demo ? "q*" : "initial average", (met - reference).norm());
    status = (met - reference).norm() < kMeanTolerance_m ? 0 : 1;
  }
  if (csv.is_open()) {
    csv.close();
    if (!csv) {
      std::fprintf(stderr, "swarm-preview: --csv: %s was not written completely (disk full?)\n",
                   opt.csv.c_str());
      return 3;
    }
  }
  return status;
}
