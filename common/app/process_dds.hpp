#pragma once

#include <atomic>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "common/app/process_options.hpp"
#include "common/dds/dds_bus.hpp"

namespace qswarm {

// A process's DDS side as its run's plan says: the participant's settings (discovery, ports,
// transports, its keystore identity) and its state bus's (routing, reader room, multicast group).
DdsOptions dds_options(const RunConfig& rc, const std::string& participant_name,
                       const ProcessOptions& o);

// Where this process flies, as its samples tell the recorder (StateMessage::host): "NAME/ADDRESS",
// its host name and the address its DDS traffic binds to (where it binds to every interface, as
// in a pod, the first one that is not loopback), cut to the wire's bound.
std::string host_label(const std::string& interface);

// What a process does when a signal stops it while it waits for its peer hosts' names.
enum class StoppedWaiting {
  kExit,    // an agent: a stop, not a failure (exit 0)
  kRecord,  // the supervisor: a participant that reaches no one, so the run still ends recorded
};

// Whether a secure run's keystore holds what a process speaking as `identity` needs (Keystore::
// check), first thing, before the process writes or waits for anything; if not, it says why on
// stderr after `prog` (the caller exits 2). A plain run's: true.
bool keystore_ready(const char* prog, const RunConfig& rc, const std::string& identity);

// dds_options, made ready to fly: the identity it speaks as in a secure run (checked by
// keystore_ready), and --peer-hosts resolved (waiting for the names as the plan says, and saying
// what it found through `say`). `exit_code` >= 0: nothing to fly; exit with it (2: bad input,
// named on stderr after `prog`; 0: stopped while waiting).
struct ProcessDds {
  DdsOptions options;
  int exit_code = -1;
};
ProcessDds process_dds(const char* prog, const RunConfig& rc, const ProcessOptions& o,
                       const std::string& participant_name, const std::string& identity,
                       const std::atomic<bool>& stop, StoppedWaiting when_stopped,
                       const std::function<void(const std::string&)>& say);

// The addresses of --peer-hosts (comma-separated names or IPv4 addresses), asked again every half
// second until they are `want` (the run's processes: every agent replica and the supervisor, this
// one included) or `timeout_s` has passed: a process started early waits for the others' names.
// `say` hears progress every 10 s, and what it found once at the end. It returns at once, with
// what it has, when `stop` is set (a signal). Empty: none of the names resolved. Discovery is
// symmetric: a peer that comes up later finds this one in its own list.
std::vector<std::string> find_peer_hosts(const std::string& names, std::size_t want,
                                         double timeout_s, const std::atomic<bool>& stop,
                                         const std::function<void(const std::string&)>& say);

}  // namespace qswarm
