#include "common/app/process_dds.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <thread>

#include <unistd.h>

#include "common/security/keystore.hpp"
#include "common/transport/port_plan.hpp"
#include "common/transport/state_message.hpp"

namespace qswarm {

DdsOptions dds_options(const RunConfig& rc, const std::string& participant_name,
                       const ProcessOptions& o) {
  const RunPlan& plan = rc.plan;
  DdsOptions d;
  ParticipantOptions& p = d.participant;
  p.domain_id = rc.transport.domain_id;
  p.name = participant_name;
  p.interface = plan.hosts.interface;
  if (plan.discovery == DiscoveryMode::kServer) p.discovery_server = plan.hosts.discovery_server;
  p.shared_memory = rc.transport.shared_memory;
  p.test_drop_data_percent = static_cast<std::uint8_t>(rc.faults.transport_drop_percent);
  p.participant_id = o.participant_id;
  if (plan.hosts.unicast_block) {
    p.unicast_peers_first = plan.hosts.unicast_block->first;
    p.unicast_peers_count = plan.hosts.unicast_block->second;
  }
  if (plan.discovery == DiscoveryMode::kPeerHosts) {
    // One participant per host (a container): id 0 of the port plan, everywhere.
    if (p.participant_id < 0) p.participant_id = 0;
    if (!plan.hosts.unicast_block) {
      p.unicast_peers_first = 0;
      p.unicast_peers_count = 1;
    }
  }
  p.keystore = rc.transport.keystore;  // the caller names the identity
  p.announce_period_s = plan.participant_announce_period_s;
  StateBusOptions& s = d.state;
  s.max_agents = plan.reader_agents;
  s.run_id = rc.transport.run_id;
  s.law = expected_law(rc.agent.law.law);
  for (const auto& a : rc.agents) s.roster.push_back(a.id);
  s.routing = plan.routing;
  s.multicast_group = plan.multicast_group;
  d.claims_kept = plan.claim_capacity;
  return d;
}

std::string host_label(const std::string& interface) {
  char name[256] = {};
  if (::gethostname(name, sizeof name - 1) != 0) std::snprintf(name, sizeof name, "unknown");
  std::string address = interface;
  if (address.empty()) {
    for (const std::string& a : local_ipv4_addresses())
      if (a.rfind("127.", 0) != 0) {
        address = a;
        break;
      }
    if (address.empty()) address = "127.0.0.1";
  }
  std::string label = std::string(name) + "/" + address;
  for (char& c : label)
    if (c < 0x20 || c > 0x7e || c == ',' || c == '"') c = '_';
  if (label.size() > kMaxHostBytes)
    label.erase(0, label.size() - kMaxHostBytes);  // keep the address
  return label;
}

bool keystore_ready(const char* prog, const RunConfig& rc, const std::string& identity) {
  if (rc.transport.keystore.empty()) return true;
  try {
    Keystore(rc.transport.keystore).check({identity});
    return true;
  } catch (const KeystoreError& e) {
    std::fprintf(stderr, "%s: transport.keystore: %s\n", prog, e.what());
    return false;
  }
}

ProcessDds process_dds(const char* prog, const RunConfig& rc, const ProcessOptions& o,
                       const std::string& participant_name, const std::string& identity,
                       const std::atomic<bool>& stop, StoppedWaiting when_stopped,
                       const std::function<void(const std::string&)>& say) {
  ProcessDds d;
  d.options = dds_options(rc, participant_name, o);
  if (!rc.transport.keystore.empty()) d.options.participant.identity = identity;
  if (rc.plan.discovery != DiscoveryMode::kPeerHosts) return d;
  std::vector<std::string>& at = d.options.participant.unicast_peer_hosts;
  at = find_peer_hosts(o.peer_hosts, rc.plan.peer_host_addresses, rc.plan.peer_hosts_wait_s, stop,
                       say);
  if (stop && when_stopped == StoppedWaiting::kExit) {
    d.exit_code = 0;
  } else if (at.empty() && stop) {
    at = {"127.0.0.1"};  // reaches no one: the run ends "interrupted", with its record
  } else if (at.empty()) {
    std::fprintf(stderr, "%s: --peer-hosts (QSWARM_PEER_HOSTS): none of %s resolves after %.0f s\n",
                 prog, o.peer_hosts.c_str(), rc.plan.peer_hosts_wait_s);
    d.exit_code = 2;
  }
  return d;
}

std::vector<std::string> find_peer_hosts(const std::string& names, std::size_t want,
                                         double timeout_s, const std::atomic<bool>& stop,
                                         const std::function<void(const std::string&)>& say) {
  const auto start = std::chrono::steady_clock::now();
  const auto waited = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  double next_say_s = 10.0;
  std::vector<std::string> found;
  for (;;) {
    found.clear();
    std::string missing;
    for (const std::string& name : split_names(names)) {
      int error = 0;
      const std::vector<std::string> at = ipv4_addresses(name, error);
      if (at.empty()) missing += (missing.empty() ? "" : ", ") + name;
      for (const std::string& a : at)
        if (std::find(found.begin(), found.end(), a) == found.end()) found.push_back(a);
    }
    const double t = waited();
    if (found.size() >= want) {
      if (say)
        say("peer hosts " + names + ": " + std::to_string(found.size()) + " addresses after " +
            std::to_string(static_cast<int>(t)) + " s: discovery by unicast there");
      return found;
    }
    const std::string line = "peer hosts " + names + ": " + std::to_string(found.size()) + " of " +
                             std::to_string(want) + " addresses after " +
                             std::to_string(static_cast<int>(t)) + " s" +
                             (missing.empty() ? "" : " (not resolved yet: " + missing + ")");
    if (stop) return found;
    if (t >= timeout_s) {
      if (say && !found.empty()) say(line + "; going on with these: the others find this one");
      return found;
    }
    if (say && t >= next_say_s) {
      say(line);
      next_say_s += 10.0;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
}

}  // namespace qswarm
