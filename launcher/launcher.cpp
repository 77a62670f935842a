#include "launcher/launcher.hpp"

#include <signal.h>
#include <sys/wait.h>

#include <cstdio>
#include <fstream>
#include <stdexcept>

namespace qswarm {
namespace {

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6f", v);
  return buf;
}

bool planned_kill_status(int status) { return WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL; }

}  // namespace

Launcher::Launcher(LaunchSpec spec, ChildProcesses& procs, Clock& clock,
                   std::function<bool()> supervisor_ready)
    : spec_(std::move(spec)),
      procs_(procs),
      clock_(clock),
      supervisor_ready_(std::move(supervisor_ready)) {}

double Launcher::wall_limit_s() const {
  return spec_.rc.judge.duration_s / spec_.time_scale + 120.0;
}

std::vector<std::string> Launcher::supervisor_argv() const {
  std::vector<std::string> a = {spec_.bin_dir + "/swarm-supervisor",
                                "--scenario",
                                spec_.scenario_path,
                                "--run-dir",
                                spec_.run_dir,
                                "--time-scale",
                                num(spec_.time_scale)};
  if (spec_.progress) a.push_back("--progress");
  return a;
}

std::vector<std::string> Launcher::agent_argv(AgentId id, double join_at_s, bool restart) const {
  std::vector<std::string> a = {spec_.bin_dir + "/swarm-agent",
                                "--scenario",
                                spec_.scenario_path,
                                "--id",
                                std::to_string(id),
                                "--run-dir",
                                spec_.run_dir,
                                "--time-scale",
                                num(spec_.time_scale)};
  if (join_at_s >= 0) {
    a.push_back("--join-at");
    a.push_back(num(join_at_s));
  }
  if (restart) a.push_back("--restart");
  a.push_back("--wait-supervisor");
  for (unsigned ign : spec_.ignore_sigterm)
    if (ign == id) a.push_back("--ignore-sigterm");
  return a;
}

std::string Launcher::agent_log(AgentId id, int life) const {
  return spec_.run_dir + "/agent-" + std::to_string(id) +
         (life ? "-restart" + std::to_string(life) : "") + ".out";
}

void Launcher::start() {
  started_s_ = clock_.now_s();
  // Its errors reach the user even when its output goes to a file (that file may be what failed).
  procs_.spawn("supervisor", 0, supervisor_argv(),
               spec_.progress ? "" : spec_.run_dir + "/supervisor.out", true);
  // The supervisor's reader first, so that it records the start.
  const double ready_by = clock_.now_s() + spec_.supervisor_ready_timeout_s;
  while (!supervisor_ready_() && clock_.now_s() < ready_by && procs_.children().front().running) {
    procs_.reap();
    clock_.sleep_until(clock_.now_s() + 0.005);
  }
  procs_.reap();
  const ChildProcesses::Child sup = procs_.children().front();
  if (!sup.running || !supervisor_ready_()) {
    // Without a recorder there is no run: start no agent.
    throw std::runtime_error(
        "the supervisor did not come up (" +
        (sup.running ? "no reader after " + num(spec_.supervisor_ready_timeout_s) + " s"
                     : describe_status(sup.status)) +
        ")" + (spec_.progress ? "" : "; see " + spec_.run_dir + "/supervisor.out"));
  }
  for (const AgentSpec& a : spec_.rc.agents)
    procs_.spawn("agent", a.id, agent_argv(a.id, -1.0, false), agent_log(a.id, 0));
  std::ofstream pids(spec_.run_dir + "/processes.csv");
  pids << "role,id,pid\n";
  for (const auto& c : procs_.children()) pids << c.role << ',' << c.id << ',' << c.pid << '\n';
}

void Launcher::note_abnormal(const ChildProcesses::Child& c, bool at_teardown) {
  const std::string who = c.role == "agent" ? "agent " + std::to_string(c.id) : c.role;
  problems_.push_back(who + " " + describe_status(c.status) +
                      (at_teardown ? " at teardown" : " during the run"));
}

void Launcher::on_agent_exit(const ChildProcesses::Child& c) {
  const std::vector<double> restarts = spec_.rc.faults.restarts_of(c.id);
  int& life = lives_[c.id];
  // A SIGKILL is the plan's when the agent marked it before killing itself (a line in
  // agent-ID.planned-kills); a SIGKILL from outside, even while planned kills are left, is not.
  const bool planned = planned_kill_status(c.status) &&
                       kills_seen_[c.id] < planned_kills_marked(spec_.run_dir, c.id) &&
                       kills_seen_[c.id] < static_cast<int>(spec_.rc.faults.kills_of(c.id).size());
  if (planned) ++kills_seen_[c.id];
  if (planned && life < static_cast<int>(restarts.size())) {
    // Its planned kill: a new process rejoins at the planned restart time.
    const double at = restarts[static_cast<std::size_t>(life)];
    ++life;
    std::fprintf(stderr, "swarm run: restarting agent %u (joins at t=%.2f s)\n", c.id, at);
    procs_.spawn("agent", c.id, agent_argv(c.id, at, true), agent_log(c.id, life));
    std::ofstream(spec_.run_dir + "/processes.csv", std::ios::app)
        << "agent," << c.id << ',' << procs_.children().back().pid << '\n';
    return;
  }
  const bool clean = WIFEXITED(c.status) && WEXITSTATUS(c.status) == 0;
  if (!planned && !clean) note_abnormal(c, false);
  if (spec_.stop_on_agent_exit && why_.empty()) why_ = "agent " + std::to_string(c.id) + " exited";
}

std::optional<std::string> Launcher::poll(bool interrupted) {
  for (const auto& c : procs_.reap()) {
    if (c.role == "agent") {
      std::fprintf(stderr, "swarm run: agent %u %s\n", c.id, describe_status(c.status).c_str());
      on_agent_exit(c);
    }
  }
  if (!procs_.children().front().running) return why_.empty() ? "supervisor finished" : why_;
  if (interrupted) return "interrupted";
  if (!why_.empty()) return why_;
  if (clock_.now_s() - started_s_ > wall_limit_s()) return "the supervisor did not finish in time";
  return std::nullopt;
}

int Launcher::stop() {
  std::vector<bool> was_running;
  for (const auto& c : procs_.children()) was_running.push_back(c.running);
  const int killed = procs_.terminate_all(spec_.grace_s);
  const auto& children = procs_.children();
  for (std::size_t i = 0; i < children.size(); ++i) {
    const auto& c = children[i];
    if (!was_running[i] || c.killed_at_teardown) continue;
    // A child that stopped on our SIGTERM exits 0 (agents, supervisor) or by SIGTERM; anything
    // else (an abort, a segfault, a non-zero exit) is a crash the record must not hide.
    const bool clean =
        (WIFEXITED(c.status) &&
         (WEXITSTATUS(c.status) == 0 || (c.role == "supervisor" && WEXITSTATUS(c.status) == 1))) ||
        (WIFSIGNALED(c.status) && WTERMSIG(c.status) == SIGTERM);
    if (!clean) note_abnormal(c, true);
  }
  return killed;
}

int Launcher::supervisor_status() const { return procs_.children().front().status; }

}  // namespace qswarm
