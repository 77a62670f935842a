#pragma once

#include <functional>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/clock/clock.hpp"
#include "common/record/run_dir.hpp"
#include "common/runtime/restart_policy.hpp"
#include "common/scenario/run_config.hpp"
#include "launcher/process_group.hpp"

namespace qswarm {

// How `swarm run` starts one run (the resolved scenario is in `rc`).
struct LaunchSpec {
  RunConfig rc;
  RunDir dir;           // absolute; the scenario as run is written there
  std::string bin_dir;  // where swarm-agent and swarm-supervisor are (the time scale: rc.plan's)
  double grace_s = 5.0;
  bool progress = true;  // the supervisor prints a live line (else its output goes to a file)
  bool stop_on_agent_exit = false;
  std::vector<unsigned> ignore_sigterm;  // (tests) agents started with --ignore-sigterm
  double supervisor_ready_timeout_s = 20.0;
  // The first of the run's participant ids in the port plan: the supervisor takes it, agent k (in
  // the scenario's order) the k-th after it. -1: Fast DDS picks (tests without processes).
  int participant_base = -1;
  // The participant ids of the run's own Discovery Servers (transport.discovery SERVER; the
  // launcher starts `swarm-discovery` on each id's ports before anything else, and tells every
  // process all of them, in this order), or none for simple discovery.
  std::vector<int> discovery_ids;
  // Whether the run's Discovery Server `server` (its place in discovery_ids) listens; unset: as
  // soon as started.
  std::function<bool(int server)> discovery_ready;
  double discovery_ready_timeout_s = 20.0;
  // (tests) servers that stop themselves (SIGSTOP) once they listen: a hung server, as Fast DDS
  // 2.9.1's can hang (W5), relays nothing and ignores SIGTERM.
  std::vector<int> hung_servers;
  int view_port = -1;  // the supervisor serves the live view on this port (-1: no view)
  std::string view_listen = "127.0.0.1";
  // What the run was predicted to ask of this host (run_load.hpp): written into its summary.
  std::optional<plan::Load> load;
};

// The supervisor refused its input (it exited 2 before it listened: a --view port another
// program took since swarm run looked, say): bad input, nothing flew. It said why on stderr.
class SupervisorRefused : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The launcher as a unit: it starts the supervisor and, once it listens, one process per agent;
// respawns an agent that died by its planned kill so that it rejoins at its restart time; ends the
// run when the supervisor ends, on a signal, or at the wall limit; and tears everything down.
// Processes and time are injected, so the policy is tested without processes or waiting.
class Launcher {
 public:
  Launcher(LaunchSpec spec, ChildProcesses& procs, Clock& clock,
           std::function<bool()> supervisor_ready);

  // Starts the supervisor, waits until it listens, then starts every agent. Throws
  // std::runtime_error (saying why) if the supervisor does not come up, SupervisorRefused if it
  // exited 2; no agent is started then.
  void start();
  // What poll() says when the supervisor ended the run itself (not an end to report).
  static constexpr const char* kFinished = "supervisor finished";
  // One pass of the watch loop. Returns why the run is over, or nothing while it goes on.
  std::optional<std::string> poll(bool interrupted);
  // Tears everything down (SIGTERM, grace, SIGKILL). Returns how many needed SIGKILL.
  int stop();
  // After stop(): the run's exit code, with the record made honest. The launcher writes the
  // summary if the supervisor died first, and amends it with what only the launcher saw: a child
  // that crashed, an agent that wrote no stats (killed after the grace period). 0 converged, 1 not,
  // 3 the record is incomplete. `lines` says why, for the user.
  struct Outcome {
    int exit_code = 1;
    std::vector<std::string> lines;
  };
  Outcome conclude(double wall_time_s);

  // Lines for the user about children that exited abnormally (reported as they happen and at
  // teardown): a crash anywhere makes the run's exit code non-zero.
  const std::vector<std::string>& problems() const { return problems_; }
  // The supervisor's waitpid status (valid once it exited).
  int supervisor_status() const;
  double wall_limit_s() const;
  std::vector<std::string> agent_argv(AgentId id, double join_at_s, bool restart) const;
  std::vector<std::string> supervisor_argv() const;
  std::vector<std::string> discovery_argv(int server) const;
  void add_unicast_peers(std::vector<std::string>& argv) const;
  // "HOST:PORT,HOST:PORT" of the run's Discovery Servers, "" without one.
  std::string discovery_address() const;
  // What the launcher saw that did not change the outcome: a server that hung or died while
  // another served to the end (known after stop()). conclude() writes them into the summary.
  const std::vector<std::string>& notes() const { return notes_; }

 private:
  static constexpr const char* kLate = "the supervisor did not finish in time";
  std::optional<std::string> next_end(bool interrupted);
  void on_agent_exit(const ChildProcesses::Child& c);
  void note_abnormal(const ChildProcesses::Child& c, bool at_teardown);
  const ChildProcesses::Child& supervisor() const;
  void start_discovery();
  std::string server_name(unsigned server) const;
  // A server lost (by place): what happened to it, and what that cost if no other server served
  // to the end. stop() judges them once every server's end is known: a note while another
  // stopped when asked (so it had not hung), else a problem.
  void lose_server(unsigned server, const std::string& what, const std::string& consequence = "");
  // A server that exited (`when`: " during the run", ...): said now, judged at stop().
  void lose_exited_server(const ChildProcesses::Child& c, const char* when);
  // procs_.reap() while the run starts: a server lost then is lost as any other.
  void reap_while_starting();
  // The child of that role and id (throws std::logic_error if none was started).
  const ChildProcesses::Child& child(const std::string& role, unsigned id) const;

  LaunchSpec spec_;
  ChildProcesses& procs_;
  Clock& clock_;
  std::function<bool()> supervisor_ready_;
  double started_s_ = 0.0;
  RestartPolicy restarts_;
  std::vector<AgentId> at_teardown_;  // agents whose life was still running at teardown
  std::string why_;
  std::string end_;  // what poll() last said ended the run
  std::vector<std::string> problems_;
  std::vector<std::string> notes_;
  struct LostServer {
    unsigned server;
    std::string what, consequence;
  };
  std::vector<LostServer> servers_lost_;  // to judge at stop()
};

}  // namespace qswarm
