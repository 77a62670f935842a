#include "launcher/launcher.hpp"

#include <signal.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <stdexcept>

#include "common/mcap/file_check.hpp"
#include "common/transport/port_plan.hpp"

namespace qswarm {
namespace {

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6f", v);
  return buf;
}

bool planned_kill_status(int status) { return WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL; }

// run.mcap ends with a footer only when the supervisor closed it: a supervisor killed mid-run
// leaves it cut short, and the record must say so ("" when it is whole).
std::string mcap_problem(const RunDir& dir) {
  const mcap::FileCheck c = mcap::check_file(dir.mcap());
  if (c.complete) return "";
  return "record incomplete: " + dir.mcap().filename().string() + ": " + c.problem;
}

}  // namespace

Launcher::Launcher(LaunchSpec spec, ChildProcesses& procs, Clock& clock,
                   std::function<bool()> supervisor_ready)
    : spec_(std::move(spec)),
      procs_(procs),
      clock_(clock),
      supervisor_ready_(std::move(supervisor_ready)),
      restarts_(spec_.rc.faults) {}

double Launcher::wall_limit_s() const { return spec_.rc.plan.launcher_wall_limit_s; }

std::vector<std::string> Launcher::supervisor_argv() const {
  std::vector<std::string> a = {spec_.bin_dir + "/swarm-supervisor",
                                "--scenario",
                                spec_.dir.scenario().string(),
                                "--run-dir",
                                spec_.dir.str(),
                                "--time-scale",
                                num(spec_.rc.plan.hosts.time_scale)};
  if (spec_.progress) a.push_back("--progress");
  if (spec_.view_port >= 0) {
    a.insert(a.end(),
             {"--view", std::to_string(spec_.view_port), "--view-listen", spec_.view_listen});
  }
  if (spec_.participant_base >= 0) {
    a.push_back("--participant-id");
    a.push_back(std::to_string(spec_.rc.plan.supervisor_participant(spec_.participant_base)));
  }
  if (!spec_.discovery_ids.empty()) {
    a.push_back("--discovery-server");
    a.push_back(discovery_address());
  }
  add_unicast_peers(a);
  return a;
}

void Launcher::add_unicast_peers(std::vector<std::string>& a) const {
  // The block: the supervisor, then every agent the run may start.
  if (spec_.participant_base < 0 || spec_.rc.plan.discovery != DiscoveryMode::kUnicastBlock) return;
  a.push_back("--unicast-peers");
  a.push_back(std::to_string(spec_.participant_base) + ":" +
              std::to_string(spec_.rc.plan.participants));
}

std::string Launcher::discovery_address() const {
  std::string list;
  for (const int id : spec_.discovery_ids) {
    if (!list.empty()) list += ',';
    list += spec_.rc.transport.interface + ":" +
            std::to_string(PortPlan::discovery_port(spec_.rc.transport.domain_id, id));
  }
  return list;
}

std::vector<std::string> Launcher::discovery_argv(int server) const {
  // Each server is told the whole list and its place in it: it connects to the others, and
  // takes the GUID prefix every client expects at that place.
  std::vector<std::string> a = {spec_.bin_dir + "/swarm-discovery",
                                "--servers",
                                discovery_address(),
                                "--index",
                                std::to_string(server),
                                "--domain",
                                std::to_string(spec_.rc.transport.domain_id),
                                "--participant-id",
                                std::to_string(spec_.discovery_ids.at(server)),
                                "--ready-file",
                                spec_.dir.discovery_ready(server).string(),
                                "--nice",
                                std::to_string(spec_.rc.plan.server_nice)};
  if (std::count(spec_.hung_servers.begin(), spec_.hung_servers.end(), server))
    a.push_back("--test-hang");
  return a;
}

std::string Launcher::server_name(unsigned server) const {
  return spec_.discovery_ids.size() > 1 ? "Discovery Server " + std::to_string(server)
                                        : std::string("the Discovery Server");
}

void Launcher::lose_server(unsigned server, const std::string& what,
                           const std::string& consequence) {
  servers_lost_.push_back({server, what, consequence});
}

void Launcher::lose_exited_server(const ChildProcesses::Child& c, const char* when) {
  std::fprintf(stderr, "swarm run: %s %s\n", server_name(c.id).c_str(),
               describe_status(c.status).c_str());
  lose_server(c.id, describe_status(c.status) + when);
}

void Launcher::reap_while_starting() {
  for (const auto& c : procs_.reap())
    if (c.role == "discovery") lose_exited_server(c, " while the run started");
}

const ChildProcesses::Child& Launcher::child(const std::string& role, unsigned id) const {
  for (const auto& c : procs_.children())
    if (c.role == role && c.id == id) return c;
  throw std::logic_error("launcher: no " + role + " " + std::to_string(id) + " started");
}

const ChildProcesses::Child& Launcher::supervisor() const { return child("supervisor", 0); }

std::vector<std::string> Launcher::agent_argv(AgentId id, double join_at_s, bool restart) const {
  std::vector<std::string> a = {spec_.bin_dir + "/swarm-agent",
                                "--scenario",
                                spec_.dir.scenario().string(),
                                "--id",
                                std::to_string(id),
                                "--run-dir",
                                spec_.dir.str(),
                                "--time-scale",
                                num(spec_.rc.plan.hosts.time_scale)};
  if (join_at_s >= 0) {
    a.push_back("--join-at");
    a.push_back(num(join_at_s));
  }
  if (restart) a.push_back("--restart");
  a.push_back("--wait-supervisor");
  if (!spec_.discovery_ids.empty()) {
    a.push_back("--discovery-server");
    a.push_back(discovery_address());
  }
  if (spec_.participant_base >= 0) {
    // Its own place in the port plan, the same for every life (a dead process frees its ports).
    int index = 0;
    while (index < static_cast<int>(spec_.rc.agents.size()) && spec_.rc.agents[index].id != id)
      ++index;
    a.push_back("--participant-id");
    a.push_back(std::to_string(
        spec_.rc.plan.agent_participant(spec_.participant_base, static_cast<std::size_t>(index))));
  }
  add_unicast_peers(a);
  for (unsigned ign : spec_.ignore_sigterm)
    if (ign == id) a.push_back("--ignore-sigterm");
  return a;
}

void Launcher::start_discovery() {
  const int servers = static_cast<int>(spec_.discovery_ids.size());
  for (int k = 0; k < servers; ++k)
    procs_.spawn("discovery", static_cast<unsigned>(k), discovery_argv(k),
                 spec_.dir.discovery_out(k).string());
  const auto server = [&](int k) -> const ChildProcesses::Child& {
    return child("discovery", static_cast<unsigned>(k));
  };
  const double since = clock_.now_s(), ready_by = since + spec_.discovery_ready_timeout_s;
  // Once seen ready a server is: one that dies after that is a loss the run's record shows. The
  // run starts with every server or not at all (one that cannot come up is the host's problem).
  std::vector<bool> up(static_cast<std::size_t>(servers), false);
  for (;;) {
    bool all = true, dead = false;
    for (int k = 0; k < servers; ++k) {
      if (!up[k]) up[k] = !spec_.discovery_ready || spec_.discovery_ready(k);
      all = all && up[k];
      dead = dead || (!up[k] && !server(k).running);
    }
    if (all || dead || clock_.now_s() >= ready_by) break;
    reap_while_starting();
    clock_.sleep_until(clock_.now_s() + 0.005);
  }
  reap_while_starting();
  // A server that died is the reason, before one still starting.
  int failed = -1;
  for (int k = 0; k < servers; ++k) {
    if (up[k]) continue;
    if (failed < 0 || (server(failed).running && !server(k).running)) failed = k;
  }
  if (failed < 0) return;
  const ChildProcesses::Child& c = server(failed);
  throw std::runtime_error(server_name(static_cast<unsigned>(failed)) + " did not come up (" +
                           (c.running ? "not listening after " + num(clock_.now_s() - since) + " s"
                                      : describe_status(c.status)) +
                           "); see " + spec_.dir.discovery_out(failed).string());
}

void Launcher::start() {
  started_s_ = clock_.now_s();
  // The run's Discovery Servers first: every participant finds the others through them.
  if (!spec_.discovery_ids.empty()) start_discovery();
  // Its errors reach the user even when its output goes to a file (that file may be what failed).
  procs_.spawn("supervisor", 0, supervisor_argv(),
               spec_.progress ? "" : spec_.dir.supervisor_out().string(), true);
  // The supervisor's reader first, so that it records the start.
  const double ready_by = clock_.now_s() + spec_.supervisor_ready_timeout_s;
  while (!supervisor_ready_() && clock_.now_s() < ready_by && supervisor().running) {
    reap_while_starting();
    clock_.sleep_until(clock_.now_s() + 0.005);
  }
  reap_while_starting();
  const ChildProcesses::Child sup = supervisor();
  if (!sup.running && WIFEXITED(sup.status) && WEXITSTATUS(sup.status) == 2)
    throw SupervisorRefused("the supervisor refused its input (exit 2, said above): nothing flew");
  if (!sup.running || !supervisor_ready_()) {
    // Without a recorder there is no run: start no agent.
    throw std::runtime_error(
        "the supervisor did not come up (" +
        (sup.running ? "no reader after " + num(spec_.supervisor_ready_timeout_s) + " s"
                     : describe_status(sup.status)) +
        ")" + (spec_.progress ? "" : "; see " + spec_.dir.supervisor_out().string()));
  }
  for (const AgentSpec& a : spec_.rc.agents)
    procs_.spawn("agent", a.id, agent_argv(a.id, -1.0, false), spec_.dir.agent_out(a.id, 0));
  std::ofstream pids(spec_.dir.processes());
  pids << "role,id,pid\n";
  for (const auto& c : procs_.children()) pids << c.role << ',' << c.id << ',' << c.pid << '\n';
}

void Launcher::note_abnormal(const ChildProcesses::Child& c, bool at_teardown) {
  // (A lost server is judged apart: lose_server.)
  const std::string who = c.role == "agent" ? "agent " + std::to_string(c.id) : c.role;
  problems_.push_back(who + " " + describe_status(c.status) +
                      (at_teardown ? " at teardown" : " during the run"));
}

void Launcher::on_agent_exit(const ChildProcesses::Child& c) {
  // A SIGKILL is the plan's when the agent marked it before killing itself; one from outside,
  // even while planned kills are left, is not.
  const bool planned = planned_kill_status(c.status) &&
                       restarts_.is_planned_kill(c.id, spec_.dir.planned_kills_marked(c.id));
  if (planned) {
    if (const std::optional<double> at = restarts_.after_planned_kill(c.id)) {
      // A new process rejoins at the planned restart time.
      std::fprintf(stderr, "swarm run: restarting agent %u (joins at t=%.2f s)\n", c.id, *at);
      procs_.spawn("agent", c.id, agent_argv(c.id, *at, true),
                   spec_.dir.agent_out(c.id, restarts_.restarts(c.id)));
      std::ofstream(spec_.dir.processes(), std::ios::app)
          << "agent," << c.id << ',' << procs_.children().back().pid << '\n';
      return;
    }
  }
  const bool clean = WIFEXITED(c.status) && WEXITSTATUS(c.status) == 0;
  if (!planned && !clean) note_abnormal(c, false);
  if (spec_.stop_on_agent_exit && why_.empty()) why_ = "agent " + std::to_string(c.id) + " exited";
}

std::optional<std::string> Launcher::poll(bool interrupted) {
  std::optional<std::string> why = next_end(interrupted);
  if (why) end_ = *why;
  return why;
}

std::optional<std::string> Launcher::next_end(bool interrupted) {
  for (const auto& c : procs_.reap()) {
    if (c.role == "agent") {
      std::fprintf(stderr, "swarm run: agent %u %s\n", c.id, describe_status(c.status).c_str());
      on_agent_exit(c);
    } else if (c.role == "discovery") {
      // Participants already matched fly on; with no server left, one that starts later (a
      // restart, a late joiner) finds nobody.
      lose_exited_server(c, " during the run");
    }
  }
  if (!supervisor().running) return why_.empty() ? std::string(kFinished) : why_;
  if (interrupted) return "interrupted";
  if (!why_.empty()) return why_;
  if (clock_.now_s() - started_s_ > wall_limit_s()) return std::string(kLate);
  return std::nullopt;
}

int Launcher::stop() {
  std::vector<bool> was_running;
  for (const auto& c : procs_.children()) was_running.push_back(c.running);
  const int killed = procs_.terminate_all(spec_.grace_s);
  const auto& children = procs_.children();
  for (std::size_t i = 0; i < children.size(); ++i) {
    const auto& c = children[i];
    if (!was_running[i]) continue;
    if (c.role == "agent") at_teardown_.push_back(c.id);
    if (c.killed_at_teardown && c.role == "discovery") {
      // An agent or supervisor killed so leaves its record incomplete, which conclude() says. A
      // server that ignores SIGTERM has hung: Fast DDS 2.9.1's server can spin with a writer's
      // lock held, and from then on relays nothing (docs/fast-dds-workarounds.md, W5).
      char grace[32];
      std::snprintf(grace, sizeof grace, "%g", spec_.grace_s);
      lose_server(c.id, std::string("hung: it did not stop within ") + grace + " s of SIGTERM",
                  " (a hung server relays no discovery; peers that were to meet after it hung did "
                  "not)");
      continue;
    }
    if (c.killed_at_teardown) continue;
    // A child that stopped on our SIGTERM exits 0 (agents, supervisor) or by SIGTERM; anything
    // else (an abort, a segfault, a non-zero exit) is a crash the record must not hide.
    const bool clean =
        (WIFEXITED(c.status) &&
         (WEXITSTATUS(c.status) == 0 || (c.role == "supervisor" && WEXITSTATUS(c.status) == 1))) ||
        (WIFSIGNALED(c.status) && WTERMSIG(c.status) == SIGTERM);
    if (!clean && c.role == "discovery")
      lose_server(c.id, describe_status(c.status) + " at teardown");
    else if (!clean)
      note_abnormal(c, true);
  }
  // Every server's end is known now: one that stopped when asked had not hung, so it served to
  // the end. While one did, a lost one cost nothing the record shows; with none, peers that were
  // to meet since never did, and the record must say so.
  std::string served;
  for (unsigned k = 0; k < spec_.discovery_ids.size() && served.empty(); ++k) {
    const auto is_k = [k](const LostServer& l) { return l.server == k; };
    if (std::none_of(servers_lost_.begin(), servers_lost_.end(), is_k)) served = server_name(k);
  }
  for (const LostServer& l : servers_lost_) {
    std::string line = server_name(l.server);
    line += ' ';
    line += l.what;
    if (served.empty()) {
      problems_.push_back(line + l.consequence);
    } else {
      line += "; ";
      line += served;
      notes_.push_back(line + " served to the end");
    }
  }
  servers_lost_.clear();
  return killed;
}

int Launcher::supervisor_status() const { return supervisor().status; }

Launcher::Outcome Launcher::conclude(double wall_time_s) {
  Outcome out;
  const int sup = supervisor_status();
  const RunDir& dir = spec_.dir;
  // The prediction and the launcher's notes go into whichever summary there is (the supervisor's,
  // or the one written below for it), before anything amends it; the notes are told the user too.
  const auto note_launchers = [&] {
    return (!spec_.load || dir.note_load(*spec_.load)) && (notes_.empty() || dir.add_notes(notes_));
  };
  out.lines = notes_;
  const bool supervisor_summary = dir.read_summary().has_value();
  if (supervisor_summary && !note_launchers()) {
    out.lines.push_back("cannot write the predicted load and notes into " + dir.summary().string());
    out.exit_code = 3;
    return out;
  }
  if (!supervisor_summary) {
    // The supervisor died before it could write the summary (or a stranger's file is there): the
    // launcher says why.
    std::string reason = "supervisor " + describe_status(sup);
    if (!end_.empty() && end_ != kFinished) reason = end_ + "; " + reason;
    if (const std::string p = mcap_problem(dir); !p.empty()) reason += "; " + p;
    out.lines.push_back(reason + "; the summary says so");
    out.exit_code =
        dir.write_fallback_summary(spec_.rc, reason, wall_time_s) && note_launchers() ? 1 : 3;
    return out;
  }
  if (WIFEXITED(sup) && WEXITSTATUS(sup) == 3) {
    // The supervisor named the first file it could not write; run.mcap cut short is named too.
    if (const std::string p = mcap_problem(dir); !p.empty()) out.lines.push_back(p);
    out.lines.push_back("the run record is incomplete (see above); run directory " + dir.str());
    out.exit_code = 3;
    return out;
  }
  // Every agent still running at teardown ends by writing its stats; one that did not (killed after
  // the grace period, a full disk) leaves the record incomplete.
  std::vector<std::string> missing;
  if (const std::string p = mcap_problem(dir); !p.empty()) missing.push_back(p);
  for (const AgentId id : at_teardown_) {
    if (std::filesystem::exists(dir.agent_stats(id))) continue;
    missing.push_back("record incomplete: agent " + std::to_string(id) + " wrote no " +
                      dir.agent_stats(id).filename().string() + " (stopped at teardown after " +
                      num(spec_.grace_s) + " s of grace?)");
  }
  std::vector<std::string> unseen = problems_;
  // A supervisor stopped at the wall limit wrote a summary, but not why it was stopped.
  if (end_ == kLate) {
    char limit[64];
    std::snprintf(limit, sizeof limit, " (wall limit %.0f s)", wall_limit_s());
    unseen.push_back(end_ + limit);
  }
  unseen.insert(unseen.end(), missing.begin(), missing.end());
  for (const std::string& m : missing) out.lines.push_back(m);
  // What the supervisor could not see still unmakes "converged" in the record.
  if (!unseen.empty() && !dir.amend_summary(unseen)) {
    out.lines.push_back("cannot amend " + dir.summary().string());
    out.exit_code = 3;
    return out;
  }
  if (!missing.empty()) {
    out.exit_code = 3;
    return out;
  }
  // As in the amended summary: what the supervisor could not see (a crash, the wall limit) leaves
  // the run unconverged, whatever the supervisor's own exit said.
  const bool converged = WIFEXITED(sup) && WEXITSTATUS(sup) == 0 && unseen.empty();
  out.lines.push_back(std::string(converged ? "converged" : "not converged") + "; run record in " +
                      dir.str());
  out.exit_code = converged ? 0 : 1;
  return out;
}

}  // namespace qswarm
