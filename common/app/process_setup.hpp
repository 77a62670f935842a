#pragma once

#include <spdlog/logger.h>

#include <atomic>
#include <cstddef>
#include <exception>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/dds/dds_bus.hpp"
#include "common/scenario/scenario.hpp"

namespace CLI {
class App;
}

namespace qswarm {

// What swarm-agent and swarm-supervisor share when they start.

// The flags `swarm run` passes to both processes, declared once so that they mean the same.
struct ProcessOptions {
  std::string scenario;          // --scenario (required)
  double time_scale = 1.0;       // --time-scale
  int domain = -1;               // --domain (overrides the scenario)
  std::int64_t seed = -1;        // --seed (overrides the scenario)
  std::string interface;         // --interface (overrides the scenario; "any": every interface)
  int agents = -1;               // --agents / QSWARM_AGENTS: N seeded random agents (compose)
  std::string discovery_server;  // --discovery-server / QSWARM_DISCOVERY_SERVER: HOST:PORT
  int participant_id = -1;       // --participant-id: its place in the port plan (-1: Fast DDS's)
  std::string keystore;          // --keystore / QSWARM_KEYSTORE (overrides the scenario)
  // --unicast-peers FIRST:COUNT: discover only the participant ids FIRST.. of the port plan, by
  // unicast (ParticipantOptions::unicast_peers_*); swarm run passes its block to a secure run.
  std::string unicast_peers;
  // --peer-hosts / QSWARM_PEER_HOSTS NAME,...: the unicast peers are at every address of these
  // names (compose services: each replica of one), one participant per host, so that port plan id
  // 0 and peers 0:1 go with it unless given. find_peer_hosts resolves them.
  std::string peer_hosts;
};
void add_process_options(CLI::App& app, ProcessOptions& o);

// How long a process waits for its peer hosts' names: a compose swarm of a few dozen replicas
// starting on two cores.
inline constexpr double kPeerHostsWaitS = 120.0;

// The addresses of --peer-hosts (comma-separated names or IPv4 addresses), asked again every half
// second until they are `want` (the run's processes: every agent replica and the supervisor, this
// one included) or `timeout_s` has passed: a process started early waits for the others' names.
// `say` hears progress every 10 s, and what it found once at the end. It returns at once, with
// what it has, when `stop` is set (a signal). Empty: none of the names resolved (the caller says
// so, naming the flag, and exits 2). Discovery is symmetric: a peer that comes up later finds
// this one in its own list.
std::vector<std::string> find_peer_hosts(const std::string& names, std::size_t want,
                                         double timeout_s, const std::atomic<bool>& stop,
                                         const std::function<void(const std::string&)>& say);
// What `prog` says on stderr when none of its --peer-hosts resolved (it then exits 2).
void say_peer_hosts_unresolved(const char* prog, const std::string& names);

// An exception that escapes a thread (one of Fast DDS's too: std::system_error when threads or
// memory run out) ends the process with exit code 1 and one line on stderr that names it, instead
// of an abort that the launcher can only report as a signal. Call first thing in main.
void exit_cleanly_on_uncaught_exceptions(const char* prog);

// An exception's what(), with a hint when it means the process ran out of threads or memory
// (std::system_error EAGAIN or ENOMEM, std::bad_alloc): what a main's last catch reports.
std::string describe_exception(const std::exception& e);

// Loads the scenario with the process's --domain/--seed overrides; on bad input prints
// "PROG: message" to stderr and returns nothing (the caller exits 2).
std::optional<RunConfig> load_for_process(const char* prog, const ProcessOptions& o);

// The identity a process of a secure run speaks as in `keystore`: "member" in a compose keystore
// (swarm keys --compose: one identity every replica shares, for replicas that claim their ids),
// else `own` ("agent-3", "supervisor"). Empty, with `why` naming the file, when a file it needs
// is missing or unreadable, or its certificate or the authority's is expired or not yet valid
// (signatures are Fast DDS's to check; `swarm run --secure` checks them before anything flies).
std::string keystore_identity(const std::string& keystore, const std::string& own,
                              std::string& why);
bool compose_keystore(const std::string& keystore);

// The participant settings a run implies (domain, interface unless overridden, shared memory,
// reader sizing for the swarm, the test transport's drop rate, the discovery server).
DdsOptions dds_options(const RunConfig& rc, const std::string& participant_name,
                       const ProcessOptions& o);

// The process's default logger: everything from info up to `log_path` (appended: a restarted
// agent adds to its log) and warnings to stderr; with no `log_path`, everything to stderr.
std::shared_ptr<spdlog::logger> make_process_logger(const std::string& name,
                                                    const std::string& log_path);

}  // namespace qswarm
