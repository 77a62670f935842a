#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/core/agent.hpp"
#include "common/scenario/run_config.hpp"
#include "proto/records.pb.h"

namespace qswarm {

// A run directory that cannot be claimed (exists with files, is claimed by another run, cannot be
// created). The message names the flag and says why; `swarm run` exits 2.
class RunDirError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One run's directory: the one place that names its files. The launcher, the supervisor, the agents
// and the tests all reach a file of the record through it (the figure scripts through
// python/qswarm/run_dir.py, checked against RunDir::files()).
class RunDir {
 public:
  RunDir() = default;
  explicit RunDir(std::filesystem::path path) : path_(std::move(path)) {}

  // Claims the directory one run writes its record into: `out`, or ROOT/TIMESTAMP-NAME (with -2,
  // -3, ... if taken) when `out` is empty. The directory must be new or empty; the claim is an
  // exclusive marker file (created with O_EXCL), so two runs given the same directory never both
  // write there. `flag` is how the user named it, for messages (--out, --runs, --new-run-in).
  static RunDir claim(const std::string& out, const std::string& scenario_name,
                      const std::string& timestamp, const std::filesystem::path& root = "runs",
                      const std::string& flag = "--out");

  const std::filesystem::path& path() const { return path_; }
  std::string str() const { return path_.string(); }
  bool empty() const { return path_.empty(); }

  std::filesystem::path marker() const { return file(kMarker); }
  std::filesystem::path scenario() const { return file(kScenario); }
  std::filesystem::path plan() const { return file(kPlan); }
  std::filesystem::path summary() const { return file(kSummary); }
  std::filesystem::path telemetry() const { return file(kTelemetry); }
  std::filesystem::path graph() const { return file(kGraph); }
  std::filesystem::path events() const { return file(kEvents); }
  std::filesystem::path records() const { return file(kRecords); }
  std::filesystem::path mcap() const { return file(kMcap); }
  std::filesystem::path processes() const { return file(kProcesses); }
  std::filesystem::path supervisor_ready() const { return file(kSupervisorReady); }
  std::filesystem::path supervisor_log() const { return file(kSupervisorLog); }
  std::filesystem::path supervisor_out() const { return file(kSupervisorOut); }
  // The output of the run's Discovery Server `server` (0 or 1), and the file it writes once it
  // listens.
  std::filesystem::path discovery_out(int server) const;
  std::filesystem::path discovery_ready(int server) const;
  std::filesystem::path plots() const { return file(kPlots); }
  std::filesystem::path view_url() const { return file(kViewUrl); }
  std::filesystem::path agent_log(AgentId id) const;
  // The agent's process output: its first life's, or the k-th restart's.
  std::filesystem::path agent_out(AgentId id, int life) const;
  std::filesystem::path agent_stats(AgentId id) const;
  // The line an agent appends before it carries out a planned kill, so that the launcher tells the
  // plan's SIGKILL from one sent from outside.
  std::filesystem::path planned_kills(AgentId id) const;

  // The scenario as run (defaults filled in, agents listed), and the plan it flies by. False if
  // it could not be written.
  bool write_scenario(const scenario::Scenario& resolved) const;
  bool write_plan(const plan::RunPlan& plan) const;
  // Where the supervisor serves the run's live view ("http://127.0.0.1:8765/"), and back (""
  // when there is none yet).
  bool write_view_url(const std::string& url) const;
  std::string read_view_url() const;
  // Appends a planned kill at simulated time t_s (false if it could not be written: the launcher
  // will then report the kill as one from outside).
  bool mark_planned_kill(AgentId id, double t_s) const;
  int planned_kills_marked(AgentId id) const;

  // summary.json written whole or not at all (write_whole), so that a process killed while
  // writing never leaves a summary cut short. False if it could not be written.
  bool write_summary(const std::string& json) const;
  // summary.json as a summary; nothing if it is missing or does not read as one.
  std::optional<records::Summary> read_summary() const;

  // When the supervisor could not write the summary (it died), the launcher writes one that says
  // why, so that a run never ends without summary.json. Returns whether it was written.
  bool write_fallback_summary(const RunConfig& rc, const std::string& reason,
                              double wall_time_s) const;
  // Problems the supervisor could not see (a crash at teardown, a file of the record missing):
  // summary.json is rewritten with converged false and the problems appended to its end_reason.
  bool amend_summary(const std::vector<std::string>& problems) const;
  // The run's predicted load (run_load.hpp) written into summary.json. False if there is no
  // summary or it could not be written.
  bool note_load(const plan::Load& load) const;
  // What the launcher saw that did not change the outcome (Summary.notes), appended.
  bool add_notes(const std::vector<std::string>& notes) const;

  // Every file name a run directory may hold, with what it is: for the docs, and for the check
  // that the figure scripts spell them the same way.
  struct File {
    const char* name;
    const char* what;
  };
  static std::vector<File> files();

  static constexpr const char* kMarker = ".swarm-run";
  static constexpr const char* kScenario = "scenario.txtpb";
  static constexpr const char* kPlan = "plan.txtpb";
  static constexpr const char* kSummary = "summary.json";
  static constexpr const char* kTelemetry = "telemetry.csv";
  static constexpr const char* kGraph = "graph.csv";
  static constexpr const char* kEvents = "events.csv";
  static constexpr const char* kRecords = "records.pb";
  static constexpr const char* kMcap = "run.mcap";
  static constexpr const char* kProcesses = "processes.csv";
  static constexpr const char* kSupervisorReady = "supervisor.ready";
  static constexpr const char* kSupervisorLog = "supervisor.log";
  static constexpr const char* kSupervisorOut = "supervisor.out";
  static constexpr const char* kPlots = "plots";
  static constexpr const char* kViewUrl = "view.url";

 private:
  // summary.json read, changed and written whole; false if there is none or it was not written.
  bool edit_summary(const std::function<void(records::Summary&)>& change) const;
  std::filesystem::path file(const char* name) const { return path_ / name; }
  std::filesystem::path path_;
};

// A scenario name as a file name: letters, digits, '.', '-', '_' kept, anything else '_', no
// leading dot, at most 64 characters ("../../x" cannot leave runs/).
std::string safe_name(const std::string& name);

// `text` into `path` whole or not at all: written to a file beside it, then renamed over it, so
// that a reader never sees it cut short and a complete file is never replaced by a partial one.
// False (and nothing left behind) if it could not be written.
bool write_whole(const std::filesystem::path& path, const std::string& text);

// The local time as run directories are named: YYYYMMDD-HHMMSS.
std::string run_timestamp();

}  // namespace qswarm
