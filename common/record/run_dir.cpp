#include "common/record/run_dir.hpp"

#include <fcntl.h>
#include <google/protobuf/text_format.h>
#include <google/protobuf/util/json_util.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <fstream>
#include <optional>
#include <sstream>

#include "proto/records.pb.h"

namespace fs = std::filesystem;

#include "common/scenario/proto_util.hpp"
#include "common/scenario/scenario.hpp"

namespace qswarm {

std::string safe_name(const std::string& name) {
  std::string out;
  for (const char c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '.' || c == '-' || c == '_';
    out += ok ? c : '_';
    if (out.size() == 64) break;
  }
  while (!out.empty() && out.front() == '.') out.front() = '_';
  return out.empty() ? "unnamed" : out;
}

namespace {

// Creates dir (if needed) and the marker; false if the marker exists (another run has it).
bool try_claim(const fs::path& dir, const std::string& flag) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw RunDirError(flag + " " + dir.string() + ": cannot create (" + ec.message() + ")");
  if (!fs::is_directory(dir, ec) || ec)
    throw RunDirError(flag + " " + dir.string() + ": not a directory");
  const fs::directory_iterator listing(dir, ec);
  if (ec) throw RunDirError(flag + " " + dir.string() + ": cannot list (" + ec.message() + ")");
  for (const auto& entry : listing) {
    if (entry.path().filename() == RunDir::kMarker) return false;
    std::string why = flag + " " + dir.string();
    why += ": expected a new or empty directory; it holds files (e.g. ";
    why += entry.path().filename().string();
    why += "): choose another ";
    why += flag;
    throw RunDirError(why);
  }
  const std::string marker = (dir / RunDir::kMarker).string();
  const int fd = ::open(marker.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) {
    if (errno == EEXIST) return false;
    throw RunDirError(flag + " " + dir.string() + ": cannot write (" + std::strerror(errno) + ")");
  }
  const std::string pid = std::to_string(::getpid()) + "\n";
  const bool ok = ::write(fd, pid.data(), pid.size()) == static_cast<ssize_t>(pid.size());
  ::close(fd);
  if (!ok) throw RunDirError(flag + " " + dir.string() + ": cannot write (disk full?)");
  return true;
}

}  // namespace

std::string run_timestamp() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y%m%d-%H%M%S", std::localtime(&t));
  return buf;
}

RunDir RunDir::claim(const std::string& out, const std::string& scenario_name,
                     const std::string& timestamp, const fs::path& root, const std::string& flag) {
  if (!out.empty()) {
    if (!try_claim(out, flag)) {
      throw RunDirError(flag + " " + out + ": another run is writing there; choose another " +
                        flag);
    }
    return RunDir(fs::absolute(out));
  }
  const fs::path base = root / (timestamp + "-" + safe_name(scenario_name));
  for (int k = 1; k < 1000; ++k) {
    const fs::path dir = k == 1 ? base : fs::path(base.string() + "-" + std::to_string(k));
    std::error_code ec;
    if (fs::exists(dir, ec)) continue;
    if (try_claim(dir, "run directory")) return RunDir(fs::absolute(dir));
  }
  throw RunDirError("run directory " + base.string() + ": no free name; use " + flag);
}

fs::path RunDir::agent_log(AgentId id) const {
  return path_ / ("agent-" + std::to_string(id) + ".log");
}

fs::path RunDir::agent_out(AgentId id, int life) const {
  return path_ / ("agent-" + std::to_string(id) +
                  (life ? "-restart" + std::to_string(life) : std::string()) + ".out");
}

fs::path RunDir::discovery_out(int server) const {
  return path_ / ("discovery-" + std::to_string(server) + ".out");
}

fs::path RunDir::discovery_ready(int server) const {
  return path_ / ("discovery-" + std::to_string(server) + ".ready");
}

fs::path RunDir::agent_stats(AgentId id) const {
  return path_ / ("agent-" + std::to_string(id) + ".stats");
}

fs::path RunDir::planned_kills(AgentId id) const {
  return path_ / ("agent-" + std::to_string(id) + ".planned-kills");
}

std::vector<RunDir::File> RunDir::files() {
  return {
      {kMarker, "the claim: created first, with O_EXCL; it holds the launcher's pid"},
      {kScenario, "the scenario as run: defaults filled in, agents listed, seed and run id"},
      {kPlan, "the run plan: what the run's size, security and hosts decided"},
      {kSummary, "the run's result (written by the launcher if the supervisor died first)"},
      {kTelemetry, "every agent sample the supervisor received and accepted"},
      {kGraph, "the graph over time"},
      {kEvents, "joins, departures, fault windows, the verdict, strangers, the end"},
      {kRecords, "samples, graph snapshots and events as length-delimited Protobuf records"},
      {kMcap, "the same records and a 3D scene as MCAP, for Foxglove or Lichtblick"},
      {kProcesses, "the pids the launcher started"},
      {kSupervisorReady, "written by the supervisor once its reader is up"},
      {kSupervisorLog, "the supervisor's log"},
      {kSupervisorOut, "the supervisor's stdout, with --quiet"},
      {"discovery-K.out", "the output of the run's Discovery Server K (0, 1; discovery SERVER)"},
      {"discovery-K.ready", "written by the run's Discovery Server K once it listens"},
      {kPlots, "swarm plot's figures (a directory; not written by the run)"},
      {kViewUrl, "where the supervisor serves the live view (with --view)"},
      {"agent-N.log", "an agent's log"},
      {"agent-N.out",
       "an agent process's stdout and stderr (agent-N-restartK.out: its K-th restart)"},
      {"agent-N.stats", "an agent's CPU, late ticks, discovery time, RSS and counters"},
      {"agent-N.planned-kills", "the planned kills an agent carried out"},
  };
}

bool write_whole(const fs::path& path, const std::string& text) {
  const fs::path tmp = path.string() + ".tmp";
  {
    std::ofstream f(tmp, std::ios::trunc);
    f << text;
    f.flush();
    if (!f) {
      std::error_code ec;
      fs::remove(tmp, ec);
      return false;
    }
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) fs::remove(tmp, ec);
  return !ec;
}

bool RunDir::write_scenario(const scenario::Scenario& resolved) const {
  return write_whole(scenario(), "# The scenario as run (defaults filled in, agents listed).\n" +
                                     to_text(resolved));
}

bool RunDir::write_plan(const plan::RunPlan& plan) const {
  std::string text;
  google::protobuf::TextFormat::PrintToString(plan, &text);
  return write_whole(this->plan(),
                     "# The run plan: what the run's size, security and hosts decided "
                     "(docs/run-plan.md).\n" +
                         text);
}

bool RunDir::write_view_url(const std::string& url) const {
  return write_whole(view_url(), url + "\n");
}

std::string RunDir::read_view_url() const {
  std::ifstream in(view_url());
  std::string line;
  std::getline(in, line);
  return line;
}

bool RunDir::mark_planned_kill(AgentId id, double t_s) const {
  std::ofstream out(planned_kills(id), std::ios::app);
  out << t_s << "\n";
  return static_cast<bool>(out.flush());
}

int RunDir::planned_kills_marked(AgentId id) const {
  std::ifstream in(planned_kills(id));
  int n = 0;
  std::string line;
  while (std::getline(in, line))
    if (!line.empty()) ++n;
  return n;
}

bool RunDir::write_fallback_summary(const RunConfig& rc, const std::string& reason,
                                    double wall_time_s) const {
  records::Summary s;
  s.set_scenario(rc.name);
  s.set_converged(false);
  s.set_convergence_time_s(-1.0);
  s.set_end_reason(reason);
  s.set_wall_time_s(wall_time_s);
  s.set_run_id(rc.transport.run_id);
  s.set_seed(static_cast<std::uint32_t>(rc.seed));
  s.set_agents_expected(static_cast<std::uint32_t>(rc.agents.size()));
  s.set_secure(!rc.transport.keystore.empty());
  s.set_law(rc.agent.law.law);
  s.set_mode(rc.agent.plant_spec().name);
  for (int k = 0; k < 3; ++k) s.add_initial_average(rc.initial_average()[k]);
  return write_summary(to_json(s));
}

bool RunDir::write_summary(const std::string& json) const { return write_whole(summary(), json); }

std::optional<records::Summary> RunDir::read_summary() const {
  std::ifstream in(summary());
  if (!in) return std::nullopt;
  std::stringstream text;
  text << in.rdbuf();
  records::Summary s;
  if (!google::protobuf::util::JsonStringToMessage(text.str(), &s).ok()) return std::nullopt;
  return s;
}

bool RunDir::edit_summary(const std::function<void(records::Summary&)>& change) const {
  std::optional<records::Summary> s = read_summary();
  if (!s) return false;
  change(*s);
  return write_summary(to_json(*s));
}

bool RunDir::amend_summary(const std::vector<std::string>& problems) const {
  return edit_summary([&](records::Summary& s) {
    s.set_converged(false);
    std::string reason = s.end_reason();
    for (const std::string& p : problems) reason += "; " + p;
    s.set_end_reason(reason);
  });
}

bool RunDir::note_load(const plan::Load& load) const {
  return edit_summary([&](records::Summary& s) { *s.mutable_load() = load; });
}

bool RunDir::add_notes(const std::vector<std::string>& notes) const {
  return edit_summary([&](records::Summary& s) {
    for (const std::string& n : notes) s.add_notes(n);
  });
}

}  // namespace qswarm
