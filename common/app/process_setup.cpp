#include "common/app/process_setup.hpp"

#include "common/app/cli_checks.hpp"
#include "common/transport/port_plan.hpp"

#include <openssl/pem.h>
#include <openssl/x509.h>
#include <spdlog/sinks/basic_file_sink.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <new>
#include <system_error>
#include <thread>
#include <utility>

namespace qswarm {

namespace {

// Past this many agents, cells are region topics (StateBusOptions::region_topics).
constexpr std::size_t kRegionTopicsAbove = 128;

// "a,b,,c" -> {"a", "b", "", "c"}; "" -> {}.
std::vector<std::string> split_names(const std::string& text) {
  std::vector<std::string> out;
  if (text.empty()) return out;
  std::size_t from = 0;
  for (;;) {
    const std::size_t comma = text.find(',', from);
    out.push_back(text.substr(from, comma == std::string::npos ? std::string::npos : comma - from));
    if (comma == std::string::npos) return out;
    from = comma + 1;
  }
}

}  // namespace

void add_process_options(CLI::App& app, ProcessOptions& o) {
  app.add_option("--scenario", o.scenario, "scenario file (Protobuf text format)")->required();
  app.add_option("--time-scale", o.time_scale, "simulated seconds per wall second")
      ->check(finite_range(0.01, 100.0));
  app.add_option("--domain", o.domain, "DDS domain id (overrides the scenario)")
      ->check(CLI::Range(0, static_cast<int>(PortPlan::kMaxDomain)));
  app.add_option("--interface", o.interface,
                 "IPv4 address DDS binds to (overrides the scenario; \"any\": every interface, "
                 "as inside a container)");
  app.add_option("--agents", o.agents,
                 "fly N seeded random agents instead of the scenario's list (compose: the swarm's "
                 "size)")
      ->envname("QSWARM_AGENTS")
      ->check(CLI::Range(1, static_cast<int>(kMaxSwarmAgents)));
  app.add_option("--discovery-server", o.discovery_server,
                 "discover through the Fast DDS Discovery Server at HOST:PORT (containers); "
                 "\"none\" or empty: simple discovery")
      ->envname("QSWARM_DISCOVERY_SERVER")
      ->transform([](const std::string& v) { return v == "none" ? std::string() : v; });
  app.add_option("--participant-id", o.participant_id,
                 "DDS participant id in the port plan (swarm run gives each process its own)")
      ->check(CLI::Range(0, PortPlan::kMaxParticipantId));
  app.add_option("--unicast-peers", o.unicast_peers,
                 "FIRST:COUNT: discover only these participant ids of the port plan, by unicast "
                 "(swarm run gives a secure run's processes its block)")
      ->check([](const std::string& v) {
        std::string why;
        return parse_unicast_peers(v, why) ? std::string() : why;
      });
  app.add_option("--peer-hosts", o.peer_hosts,
                 "NAME,...: discover by unicast the one participant at each address of these "
                 "names (secure compose: agent,supervisor)")
      ->envname("QSWARM_PEER_HOSTS")
      ->check([](const std::string& v) {
        for (const std::string& name : split_names(v)) {
          // A host name or a dotted IPv4 address: letters, digits, '-' and '.', no port.
          const bool host =
              !name.empty() && name.front() != '-' && name.front() != '.' &&
              std::all_of(name.begin(), name.end(), [](char c) {
                return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '-' || c == '.';
              });
          if (!host) {
            std::string why = "\"";
            why += name;
            why += "\" in \"";
            why += v;
            why += "\" is not a host name or an IPv4 address (NAME,NAME,... with no port)";
            return why;
          }
        }
        return std::string();
      });
  app.add_option("--seed", o.seed, "run seed (overrides the scenario)")
      ->check(CLI::Range(std::int64_t{0}, std::int64_t{4294967295}));
  app.add_option("--keystore", o.keystore,
                 "DDS-Security with this keystore (swarm keys; overrides the scenario's "
                 "transport.keystore; compose: swarm keys --compose)")
      ->envname("QSWARM_KEYSTORE");
}

namespace {

// Why keystore file `f` cannot serve now ("" if it can): missing or unreadable, and a
// certificate also not PEM, or not valid now. A compose replica has no launcher to check its
// keystore first: an expired certificate would only surface as a participant Fast DDS cannot
// create.
std::string keystore_file_problem(const std::filesystem::path& f, bool certificate) {
  if (!std::filesystem::is_regular_file(f))
    return f.string() + ": missing (swarm keys writes a keystore)";
  std::FILE* in = std::fopen(f.c_str(), "r");
  if (!in) return f.string() + ": cannot be read (" + std::strerror(errno) + ")";
  X509* cert = certificate ? PEM_read_X509(in, nullptr, nullptr, nullptr) : nullptr;
  std::fclose(in);
  if (!certificate) return {};
  if (!cert) return f.string() + ": not a PEM certificate (swarm keys writes a keystore)";
  std::string why;
  // X509_cmp_current_time: -1 before now, 1 after, 0 on a malformed time.
  if (X509_cmp_current_time(X509_get0_notBefore(cert)) >= 0)
    why = ": not valid yet (its start date is in the future)";
  else if (X509_cmp_current_time(X509_get0_notAfter(cert)) <= 0)
    why = ": expired (swarm keys --days sets how long a keystore lasts)";
  X509_free(cert);
  return why.empty() ? std::string() : f.string() + why;
}

}  // namespace

bool compose_keystore(const std::string& keystore) {
  return std::filesystem::is_directory(std::filesystem::path(keystore) / "member");
}

std::string keystore_identity(const std::string& keystore, const std::string& own,
                              std::string& why) {
  const std::filesystem::path ks(keystore);
  std::string who = own == "supervisor" || !compose_keystore(keystore) ? own : "member";
  for (const auto& [f, certificate] :
       {std::pair{ks / "ca.cert.pem", true}, std::pair{ks / "governance.p7s", false},
        std::pair{ks / who / "cert.pem", true}, std::pair{ks / who / "key.pem", false},
        std::pair{ks / who / "permissions.p7s", false}}) {
    why = keystore_file_problem(f, certificate);
    if (!why.empty()) return {};
  }
  return who;
}

std::optional<RunConfig> load_for_process(const char* prog, const ProcessOptions& opts) {
  try {
    ScenarioOverrides o;
    o.domain_id = opts.domain;
    o.seed = opts.seed;
    o.agents = opts.agents;
    o.keystore = opts.keystore;
    RunConfig rc = load_scenario(opts.scenario, o);
    // Checked (and resolved, with retries while a container network's DNS catches up) before
    // anything is created, so that a bad address is bad input: exit 2.
    if (!opts.discovery_server.empty()) resolve_discovery_server(opts.discovery_server);
    if (!opts.peer_hosts.empty() && !opts.discovery_server.empty()) {
      std::fprintf(stderr,
                   "%s: --peer-hosts (QSWARM_PEER_HOSTS) and --discovery-server "
                   "(QSWARM_DISCOVERY_SERVER): discovery by unicast to the peers, or through the "
                   "server, not both\n",
                   prog);
      return std::nullopt;
    }
    const std::string problem =
        interface_problem(opts.interface.empty() ? rc.transport.interface : opts.interface);
    if (!problem.empty()) {
      std::fprintf(stderr, "%s: %s: %s\n", prog,
                   opts.interface.empty() ? "scenario field 'transport.interface'" : "--interface",
                   problem.c_str());
      return std::nullopt;
    }
    return rc;
  } catch (const ScenarioError& e) {
    std::fprintf(stderr, "%s: %s\n", prog, e.what());
    return std::nullopt;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "%s: --discovery-server (QSWARM_DISCOVERY_SERVER): %s\n", prog, e.what());
    return std::nullopt;
  }
}

std::string describe_exception(const std::exception& e) {
  std::string what = e.what();
  const auto* sys = dynamic_cast<const std::system_error*>(&e);
  const bool out_of_resources =
      dynamic_cast<const std::bad_alloc*>(&e) != nullptr ||
      (sys != nullptr && (sys->code() == std::errc::resource_unavailable_try_again ||
                          sys->code() == std::errc::not_enough_memory));
  if (out_of_resources)
    what += " (out of threads or memory: run fewer agents, or raise the process and thread limits)";
  return what;
}

namespace {
const char* g_prog = "qswarm";

[[noreturn]] void on_terminate() {
  std::string what = "std::terminate without an exception";
  if (const std::exception_ptr e = std::current_exception()) {
    try {
      std::rethrow_exception(e);
    } catch (const std::exception& ex) {
      what = "uncaught exception: " + describe_exception(ex);
      if (creating_participant() && dynamic_cast<const std::system_error*>(&ex) != nullptr &&
          what.find("out of threads") == std::string::npos)
        what +=
            " (while Fast DDS started its participant's threads: out of threads or memory? run "
            "fewer agents, or raise the process and thread limits)";
    } catch (...) {
      what = "uncaught exception of an unknown type";
    }
  }
  std::fprintf(stderr, "%s: fatal: %s\n", g_prog, what.c_str());
  std::fflush(stderr);
  std::_Exit(1);
}
}  // namespace

void exit_cleanly_on_uncaught_exceptions(const char* prog) {
  g_prog = prog;
  std::set_terminate(on_terminate);
}

DdsOptions dds_options(const RunConfig& rc, const std::string& participant_name,
                       const ProcessOptions& o) {
  DdsOptions d;
  ParticipantOptions& p = d.participant;
  p.domain_id = rc.transport.domain_id;
  p.name = participant_name;
  p.interface = o.interface.empty() ? rc.transport.interface : o.interface;
  if (p.interface == "any") p.interface.clear();
  p.discovery_server = o.discovery_server;
  p.shared_memory = rc.transport.shared_memory;
  p.test_drop_data_percent = static_cast<std::uint8_t>(rc.faults.transport_drop_percent);
  p.participant_id = o.participant_id;
  std::string why;
  if (const auto peers = parse_unicast_peers(o.unicast_peers, why)) {
    p.unicast_peers_first = peers->first;
    p.unicast_peers_count = peers->second;
  }
  if (!o.peer_hosts.empty()) {
    // One participant per host (a container): id 0 of the port plan, everywhere.
    if (p.participant_id < 0) p.participant_id = 0;
    if (o.unicast_peers.empty()) {
      p.unicast_peers_first = 0;
      p.unicast_peers_count = 1;
    }
  }
  p.keystore = rc.transport.keystore;  // the caller names the identity
  // Everyone hears every announcement: N^2 per period. Every second up to 25 processes, then
  // slower with the swarm (10 s at 256); lost first announcements are repeated by the quick ones.
  p.announce_period_s = std::max(1.0, static_cast<double>(rc.agents.size()) / 25.0);
  StateBusOptions& s = d.state;
  s.max_agents = static_cast<int>(std::max<std::size_t>(rc.agents.size(), 16));
  s.run_id = rc.transport.run_id;
  for (const auto& a : rc.agents) s.roster.push_back(a.id);
  // A Discovery Server relays announcements by topic: with a topic per agent name, an agent that
  // hears its neighbours by name discovers only them (StateBusOptions::topic_per_name).
  s.topic_per_name = !p.discovery_server.empty();
  // And cells as partitions of region topics where one shared topic would introduce everyone to
  // everyone past the wall (StateBusOptions::region_topics says what it costs below it).
  s.region_topics = s.topic_per_name && rc.agents.size() > kRegionTopicsAbove;
  // Writers never filter for their readers (StateBusOptions::filter_at_writer says why).
  // Where everyone hears everyone on loopback, a sample is one datagram to the run's multicast
  // group rather than one per reader (docs/benchmarks.md, "One datagram per sample"). Discovery
  // is another matter (simple or through a Discovery Server alike). Not where the test
  // transport drops (its losses would hit every reader of a sample at once, no longer each link
  // on its own), nor with discovery by unicast peers (secure runs: no multicast is sent or heard
  // there), nor over shared memory (asked for by name), nor off loopback (containers, whose
  // networks carry multicast unreliably, and the fault tests' namespaces), nor where the scenario
  // turns it off (transport.multicast).
  if (rc.transport.multicast && rc.transport.delivery == Delivery::kAll &&
      p.interface.rfind("127.", 0) == 0 && p.test_drop_data_percent == 0 &&
      p.unicast_peers_count == 0 && p.keystore.empty() && !p.shared_memory)
    s.multicast_group = state_multicast_group(rc.transport.run_id);
  return d;
}

std::shared_ptr<spdlog::logger> make_process_logger(const std::string& name,
                                                    const std::string& log_path) {
  std::vector<spdlog::sink_ptr> sinks;
  auto console = std::make_shared<spdlog::sinks::stderr_color_sink_mt>();
  // With a log file, the terminal gets warnings only; without one (a container, whose log is its
  // output), everything.
  console->set_level(log_path.empty() ? spdlog::level::info : spdlog::level::warn);
  sinks.push_back(console);
  if (!log_path.empty())
    sinks.push_back(std::make_shared<spdlog::sinks::basic_file_sink_mt>(log_path, false));
  auto logger = std::make_shared<spdlog::logger>(name, sinks.begin(), sinks.end());
  logger->set_level(spdlog::level::info);
  logger->flush_on(spdlog::level::info);
  spdlog::set_default_logger(logger);
  return logger;
}

void say_peer_hosts_unresolved(const char* prog, const std::string& names) {
  std::fprintf(stderr, "%s: --peer-hosts (QSWARM_PEER_HOSTS): none of %s resolves after %.0f s\n",
               prog, names.c_str(), kPeerHostsWaitS);
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
