// Swarms across hosts (ctest label: hosts): three hosts, each a network namespace on its own
// subnet, routed through a fourth that forwards unicast only, so no multicast crosses between
// them, as on most clusters. Eight agent processes on each; the supervisor on host 0 and the
// Discovery Server on host 1, every process pointed at it by address. Needs root (CI runs as
// root): skipped elsewhere, and failed where CI is set. Last, the compose swarm on three hosts.
#include <gtest/gtest.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "tests/support/cannot_run.hpp"
#include "tests/swarm/harness.hpp"
#include "tests/swarm/net_hosts.hpp"

namespace qswarm::test {
namespace {

constexpr int kHosts = 3, kPerHost = 8, kAgents = kHosts * kPerHost;
constexpr const char* kServerPort = "11811";

#define REQUIRE_NET_HOSTS()                                                 \
  do {                                                                      \
    const std::string why = net_hosts_unavailable();                        \
    if (!why.empty()) QSWARM_CANNOT_RUN("hosts tests cannot run: " << why); \
  } while (false)

int host_of(int agent) { return (agent - 1) / kPerHost; }

// One swarm of 24 agents over the routed hosts. `gain` slows the agreement down so that a fault
// lands before it is reached (1: about a second; 0.05: about 15 s). `servers`: 1, on host 1, or 2,
// on hosts 1 and 2, every process listing both; 0: a secure swarm (below). `extra`: more of the
// scenario. A fourth host, which flies nothing, is there for a stranger.
class RoutedSwarm {
 public:
  RoutedSwarm(const std::string& name, double gain, int servers = 1, const std::string& extra = "")
      : hosts_(kHosts + 1, NetHosts::Layout::kRouted), dir_(fresh_dir(name)), servers_(servers) {
    std::filesystem::create_directories(dir_);
    scen_ = dir_ / "hosts.txtpb";
    std::ofstream f(scen_);
    f << "name: \"" << name << "\"\n";
    for (int i = 1; i <= kAgents; ++i)
      f << "agents { id: " << i << " position { x: " << (i * 7) % 19 << " y: " << (i * 5) % 17
        << " z: " << 10 + (i * 3) % 13 << " } }\n";
    f << "gain: " << gain << R"(
weight { policy: UNWEIGHTED }
topology { policy: PROXIMITY threshold_m: 1000 }
convergence { tolerance_m: 1e-6 hold_s: 1 }
duration_s: 90
seed: 5
transport { domain_id: 3 }
)" << extra;
  }
  ~RoutedSwarm() {
    for (auto& a : agents_)
      if (a) a->signal(SIGTERM);
    for (auto& a : agents_)
      if (a) a->wait(15.0);
    for (auto& server : servers_up_) {
      server->signal(SIGTERM);
      server->wait(15.0);
    }
  }
  std::string server() const {
    std::string list;
    for (int k = 0; k < servers_; ++k)
      list += (k ? "," : "") + hosts_.address(1 + k) + ":" + kServerPort;
    return list;
  }
  // How a process on `host` discovers: through the servers; or, secure (no secure Discovery Server
  // in Fast DDS 2.9), by unicast to participant ids 0..8 of the port plan on each host (the
  // agents of a host take 0..7, the supervisor 8), with the keystore.
  std::vector<std::string> discovery(int host, int participant_id) const {
    if (servers_ > 0) return {"--interface", hosts_.address(host), "--discovery-server", server()};
    std::string peers;
    for (int h = 0; h < kHosts; ++h) peers += (h ? "," : "") + hosts_.address(h);
    return {"--interface",      hosts_.address(host),
            "--keystore",       keystore().string(),
            "--peer-hosts",     peers,
            "--unicast-peers",  kSecureBlock,
            "--participant-id", std::to_string(participant_id)};
  }
  static constexpr const char* kSecureBlock = "0:9";
  std::filesystem::path keystore() const { return dir_ / "keys"; }
  std::vector<std::string> agent_argv(int id, int host) const {
    std::vector<std::string> argv = {bin("swarm-agent"), "--scenario", scen_.string(), "--id",
                                     std::to_string(id), "--run-dir",  dir_.string()};
    const auto d = discovery(host, (id - 1) % kPerHost);
    argv.insert(argv.end(), d.begin(), d.end());
    return hosts_.exec(host, argv);
  }
  // The servers first, listening, then the rest (but `skip`, started later by the test): as swarm
  // run orders its own.
  void start(int skip = 0) {
    for (int k = 0; k < servers_; ++k) {
      const auto ready = dir_ / ("discovery-" + std::to_string(k) + ".ready");
      servers_up_.push_back(std::make_unique<Child>(
          hosts_.exec(1 + k, {bin("swarm-discovery"), "--servers", server(), "--index",
                              std::to_string(k), "--domain", "3", "--ready-file", ready.string()}),
          dir_ / ("discovery-" + std::to_string(k) + ".out")));
      if (!wait_for([&] { return std::filesystem::exists(ready); }, 30.0))
        throw std::runtime_error("Discovery Server " + std::to_string(k) + " never listened");
    }
    if (servers_ == 0) {
      const Result k = run({bin("swarm"), "keys", scen_.string(), "--out", keystore().string()});
      if (k.code != 0) throw std::runtime_error("swarm keys: " + k.output);
    }
    std::vector<std::string> sup = {bin("swarm-supervisor"), "--scenario", scen_.string(),
                                    "--run-dir", dir_.string()};
    const auto d = discovery(0, kPerHost);
    sup.insert(sup.end(), d.begin(), d.end());
    sup_ = std::make_unique<Child>(hosts_.exec(0, sup), dir_ / "supervisor.out");
    agents_.resize(kAgents);
    for (int id = 1; id <= kAgents; ++id)
      if (id != skip)
        agents_[id - 1] = std::make_unique<Child>(agent_argv(id, host_of(id)),
                                                  dir_ / ("agent-" + std::to_string(id) + ".out"));
  }
  // The agents events.csv names with this kind of event.
  std::set<int> with_event(const std::string& kind) const {
    std::set<int> out;
    if (!std::filesystem::exists(dir_ / "events.csv")) return out;
    for (const auto& row : read_csv(dir_ / "events.csv"))
      if (row.at("kind") == kind) out.insert(std::stoi(row.at("agent")));
    return out;
  }
  // The swarm's clock as the supervisor recorded it: the latest stamp of a running agent.
  double swarm_clock() const {
    std::ifstream in(dir_ / "telemetry.csv");
    std::string line;
    double t = -1.0;
    std::getline(in, line);  // stamp_s,id,seq,phase,...
    while (std::getline(in, line)) {
      std::vector<std::string> f;
      std::stringstream row(line);
      for (std::string cell; f.size() < 4 && std::getline(row, cell, ',');) f.push_back(cell);
      if (f.size() == 4 && f[3] == "1") t = std::max(t, std::atof(f[0].c_str()));
    }
    return t;
  }
  bool all_in(const std::string& kind, const std::set<int>& ids) const {
    const std::set<int> have = with_event(kind);
    for (const int id : ids)
      if (!have.count(id)) return false;
    return true;
  }
  // Waits until every agent (but `skip`) joined and the swarm flew 2 s; "" or what did not happen.
  std::string flying(int skip = 0) const {
    std::set<int> all;
    for (int id = 1; id <= kAgents; ++id)
      if (id != skip) all.insert(id);
    if (!wait_for([&] { return all_in("join", all); }, 120.0)) return "not every agent joined";
    if (!wait_for([&] { return swarm_clock() >= 2.0; }, 120.0)) return "the swarm never flew";
    return "";
  }
  std::set<int> agents_on(int host) const {
    std::set<int> out;
    for (int id = 1; id <= kAgents; ++id)
      if (host_of(id) == host) out.insert(id);
    return out;
  }

  NetHosts hosts_;
  std::filesystem::path dir_, scen_;
  int servers_;
  std::vector<std::unique_ptr<Child>> servers_up_;
  std::unique_ptr<Child> sup_;
  std::vector<std::unique_ptr<Child>> agents_;  // by id - 1
};

// The last host each agent flew on, as the summary says.
std::string last_host(const records::Summary& s, unsigned id) {
  for (const auto& a : s.agents())
    if (a.id() == id && a.hosts_size() > 0) return a.hosts(a.hosts_size() - 1);
  return "";
}

TEST(Hosts, ThreeRoutedHostsWithoutMulticastConvergeAndTheRecordNamesEachHost) {
  REQUIRE_NET_HOSTS();
  RoutedSwarm w("hosts-three", 1.0);
  // No host can send multicast anywhere: there is no route for it.
  for (int h = 0; h < kHosts; ++h)
    EXPECT_NE(std::system(("ip -n " + w.hosts_.ns(std::to_string(h)) +
                           " route get 239.255.0.1 >/dev/null 2>&1")
                              .c_str()),
              0)
        << "host " << h << " has a multicast route";
  w.start();
  const Result r = w.sup_->wait(180.0);
  ASSERT_EQ(r.code, 0) << r.output;
  const records::Summary s = read_summary(w.dir_);
  EXPECT_TRUE(s.converged());
  EXPECT_EQ(s.agents_expected(), static_cast<unsigned>(kAgents));
  EXPECT_LT(s.average_relative_error(), 1e-9);
  for (unsigned id = 1; id <= kAgents; ++id) {
    const std::string host = last_host(s, id);
    const std::string want = "/" + w.hosts_.address(host_of(static_cast<int>(id)));
    EXPECT_TRUE(host.size() > want.size() &&
                host.compare(host.size() - want.size(), want.size(), want) == 0)
        << "agent " << id << " flew on \"" << host << "\", expected one ending " << want;
  }
  EXPECT_NE(r.output.find("hosts 3:"), std::string::npos) << r.output;
}

TEST(Hosts, AHostCutOffIsNamedMissingTheOthersKeepTheAverageAndItRejoins) {
  REQUIRE_NET_HOSTS();
  RoutedSwarm w("hosts-cut", 0.05);
  w.start();
  ASSERT_EQ(w.flying(), "");
  // Host 2 cut off from the others (the hub forwards nothing to or from it) until each of its
  // agents is named departed, and for a window after.
  const std::set<int> cut = w.agents_on(2);
  w.hosts_.cut_off(2, true);
  const bool departed = wait_for([&] { return w.all_in("depart", cut); }, 30.0);
  // The window: the other two hosts fly on alone for 3 s of the swarm's clock.
  const double departed_at = w.swarm_clock();
  const bool flew_on = wait_for([&] { return w.swarm_clock() >= departed_at + 3.0; }, 60.0);
  w.hosts_.cut_off(2, false);
  EXPECT_TRUE(flew_on) << "the swarm's clock stopped while host 2 was cut off";
  ASSERT_TRUE(departed) << "host 2's agents were never named departed";
  // No agent of another host was named departed.
  for (const int id : w.with_event("depart")) EXPECT_TRUE(cut.count(id)) << "agent " << id;
  EXPECT_TRUE(wait_for([&] { return w.all_in("rejoin", cut); }, 60.0))
      << "host 2's agents never rejoined";
  const Result r = w.sup_->wait(180.0);
  ASSERT_EQ(r.code, 0) << r.output;
  const records::Summary s = read_summary(w.dir_);
  EXPECT_TRUE(s.converged());
  EXPECT_EQ(s.missing_agents_size(), 0);
  // Edge-flow keeps the exact initial average through the cut and the return.
  EXPECT_LT(s.average_relative_error(), 1e-9);
  EXPECT_GE(s.departures(), static_cast<unsigned>(kPerHost));
}

TEST(Hosts, AnAgentRestartedOnAnotherHostRejoinsUnderItsIdAtItsNewAddress) {
  REQUIRE_NET_HOSTS();
  RoutedSwarm w("hosts-restart", 0.05);
  w.start();
  ASSERT_EQ(w.flying(), "");
  // Agent 20 (host 2) dies without a word, as its machine would; it comes back on host 0 with a
  // new address and recovers the flows it owned from its neighbours.
  constexpr int kMoved = 20;
  ASSERT_EQ(host_of(kMoved), 2);
  w.agents_[kMoved - 1]->signal(SIGKILL);
  w.agents_[kMoved - 1]->wait(10.0);
  ASSERT_TRUE(wait_for([&] { return w.with_event("depart").count(kMoved) > 0; }, 30.0))
      << "agent " << kMoved << " was never named departed";
  std::vector<std::string> argv = w.agent_argv(kMoved, 0);
  argv.insert(argv.end(), {"--restart", "--join-at", "0"});
  w.agents_[kMoved - 1] = std::make_unique<Child>(argv, w.dir_ / "agent-20-restart.out");
  const Result r = w.sup_->wait(180.0);
  ASSERT_EQ(r.code, 0) << r.output;
  const records::Summary s = read_summary(w.dir_);
  EXPECT_TRUE(s.converged());
  EXPECT_LT(s.average_relative_error(), 1e-9);
  EXPECT_TRUE(w.with_event("rejoin").count(kMoved));
  // The record says where it flew: host 2, then host 0.
  for (const auto& a : s.agents()) {
    if (a.id() != kMoved) continue;
    ASSERT_EQ(a.hosts_size(), 2) << a.DebugString();
    EXPECT_NE(a.hosts(0).find("/" + w.hosts_.address(2)), std::string::npos) << a.hosts(0);
    EXPECT_NE(a.hosts(1).find("/" + w.hosts_.address(0)), std::string::npos) << a.hosts(1);
  }
}

TEST(Hosts, WithOneOfTwoDiscoveryServersKilledALateJoinerIsStillFound) {
  REQUIRE_NET_HOSTS();
  // Agent 24 is not awaited at the start; its process starts only once server 0 is dead, so it
  // can find the swarm through server 1 alone.
  constexpr int kLate = 24;
  RoutedSwarm w("hosts-server-killed", 0.05, 2, "faults { late_join { agent: 24 at_s: 3 } }\n");
  w.start(kLate);
  ASSERT_EQ(w.flying(kLate), "");
  w.servers_up_[0]->signal(SIGKILL);
  w.servers_up_[0]->wait(10.0);
  w.agents_[kLate - 1] =
      std::make_unique<Child>(w.agent_argv(kLate, host_of(kLate)), w.dir_ / "agent-24.out");
  EXPECT_TRUE(wait_for([&] { return w.with_event("join").count(kLate) > 0; }, 60.0))
      << "the late joiner was never heard";
  const Result r = w.sup_->wait(180.0);
  ASSERT_EQ(r.code, 0) << r.output;
  const records::Summary s = read_summary(w.dir_);
  EXPECT_TRUE(s.converged());
  EXPECT_EQ(s.agents_expected(), static_cast<unsigned>(kAgents));
  EXPECT_EQ(s.missing_agents_size(), 0);
  // Its start is in the average everyone met at.
  EXPECT_LT(s.average_relative_error(), 1e-9);
  EXPECT_EQ(s.departures(), 0u);
}

TEST(Hosts, ASecureSwarmAcrossHostsConvergesAndAStrangerOnAFourthHostReachesNoOne) {
  REQUIRE_NET_HOSTS();
  // Secure: by unicast to each host's block of participant ids, with a keystore; a stranger on host
  // 3 (which flies nothing) announces to the same ids on every host and forges agent 3 at 200 Hz,
  // told the run id, as one who scanned the ports and read the wire would.
  RoutedSwarm w("hosts-secure", 0.3, 0);
  w.start();
  std::string peers;
  for (int h = 0; h < kHosts; ++h) peers += (h ? "," : "") + w.hosts_.address(h);
  const auto report = w.dir_ / "stranger.txt";
  Child stranger(
      w.hosts_.exec(kHosts, {bin("qswarm-attacker"), "--domain", "3", "--mode", "impersonate",
                             "--victim", "3", "--rate", "200", "--run-id", "0", "--interface",
                             w.hosts_.address(kHosts), "--peer-hosts", peers, "--unicast-peers",
                             RoutedSwarm::kSecureBlock, "--report", report.string()}),
      w.dir_ / "stranger.out");
  const Result r = w.sup_->wait(240.0);
  stranger.signal(SIGTERM);
  stranger.wait(20.0);
  ASSERT_EQ(r.code, 0) << r.output;
  const records::Summary s = read_summary(w.dir_);
  EXPECT_TRUE(s.secure());
  EXPECT_TRUE(s.converged());
  EXPECT_EQ(s.agents_expected(), static_cast<unsigned>(kAgents));
  EXPECT_LT(s.average_relative_error(), 1e-9);
  EXPECT_EQ(s.forgeries_size(), 0);
  EXPECT_EQ(s.foreign_samples(), 0u);
  std::map<std::string, std::string> said;
  std::ifstream in(report);
  for (std::string line; std::getline(in, line);)
    if (const auto eq = line.find('='); eq != std::string::npos)
      said[line.substr(0, eq)] = line.substr(eq + 1);
  EXPECT_EQ(said["heard"], "0") << read_file(w.dir_ / "stranger.out");
  EXPECT_GT(std::stoull(said["published"].empty() ? "0" : said["published"]), 500u)
      << read_file(w.dir_ / "stranger.out");
}

// The README's compose swarm on several machines (docker/docker-compose.hosts.yml), as a lab
// runs it: each routed host its own container engine (a podman service in the host's namespace,
// driven through its Docker API by docker-compose, since podman-compose 1.0.3 cannot run
// network_mode: host), host 0 running `up` (the server, the supervisor, 3 agents), hosts 1 and 2
// `up agent` (3 agents each), every container pointed at host 0's address.
class ComposeHosts {
 public:
  static constexpr int kReplicas = 3;
  ComposeHosts() : hosts_(kHosts, NetHosts::Layout::kRouted), dir_(fresh_dir("hosts-compose")) {
    std::filesystem::create_directories(dir_ / "runs");
    // The compose test's podman settings, and runc where it is (crun fails on such hosts).
    std::ofstream conf(dir_ / "containers.conf");
    conf << read_file(std::string(QSWARM_SOURCE_DIR) + "/tests/compose/containers.conf");
    if (!find_tool("runc").empty()) conf << "runtime = \"runc\"\n";
  }
  ~ComposeHosts() {
    for (int h = 0; h < kHosts && h < static_cast<int>(engines_.size()); ++h)
      run(compose(h, {"down", "--timeout", "5"}), 30.0);
    for (auto& e : engines_) {
      e->signal(SIGTERM);
      e->wait(20.0);
    }
  }
  std::string socket(int h) const { return (dir_ / ("engine-" + std::to_string(h) + ".sock")); }
  // Each host's engine, listening on a socket of its own.
  std::string start_engines() {
    for (int h = 0; h < kHosts; ++h) {
      engines_.push_back(std::make_unique<Child>(
          hosts_.exec(h, {"/usr/bin/env", "CONTAINERS_CONF=" + (dir_ / "containers.conf").string(),
                          "podman", "system", "service", "--time=0", "unix://" + socket(h)}),
          dir_ / ("engine-" + std::to_string(h) + ".out")));
      if (!wait_for([&] { return std::filesystem::exists(socket(h)); }, 60.0))
        return "host " + std::to_string(h) + "'s podman service never listened: " +
               read_file(dir_ / ("engine-" + std::to_string(h) + ".out"));
    }
    return "";
  }
  // docker-compose on host h, with what a user there would export.
  std::vector<std::string> compose(int h, const std::vector<std::string>& args) const {
    std::vector<std::string> argv = {
        "/usr/bin/env",
        "DOCKER_HOST=unix://" + socket(h),
        "QSWARM_AGENTS=" + std::to_string(kHosts * kReplicas),
        "QSWARM_REPLICAS=" + std::to_string(kReplicas),
        "QSWARM_DISCOVERY_SERVER=" + hosts_.address(0) + ":11811",
        "QSWARM_RUNS=" + (dir_ / "runs").string(),
        "QSWARM_USER=" + std::to_string(getuid()) + ":" + std::to_string(getgid()),
        "docker-compose",
        "-p",
        "qswh" + std::to_string(getpid()) + "-" + std::to_string(h),
        "-f",
        std::string(QSWARM_SOURCE_DIR) + "/docker/docker-compose.hosts.yml"};
    argv.insert(argv.end(), args.begin(), args.end());
    return argv;
  }

  NetHosts hosts_;
  std::filesystem::path dir_;
  std::vector<std::unique_ptr<Child>> engines_;
};

TEST(Hosts, TheComposeSwarmOnThreeHostsPointedAtOneServerConvergesAndNamesEachHost) {
  REQUIRE_NET_HOSTS();
  for (const char* tool : {"podman", "docker-compose"}) {
    if (find_tool(tool).empty())
      QSWARM_CANNOT_RUN("no " << tool << " (apt-get install podman docker-compose)");
  }
  // The image of the programs under test, as the compose test makes it.
  const std::string bin_dir = std::filesystem::path(bin("swarm-agent")).parent_path();
  const Result image =
      run({std::string(QSWARM_SOURCE_DIR) + "/tests/compose/image.sh", bin_dir}, 500.0);
  if (image.code == 77) QSWARM_CANNOT_RUN(image.output);
  ASSERT_EQ(image.code, 0) << "tests/compose/image.sh: " << image.output;
  ComposeHosts c;
  ASSERT_EQ(c.start_engines(), "");
  // The other machines first: their agents wait for the server, as a lab's would.
  for (int h = 1; h < kHosts; ++h) {
    const Result up = run(c.compose(h, {"up", "-d", "--no-build", "agent"}), 150.0);
    ASSERT_EQ(up.code, 0) << "host " << h << ": " << up.output;
  }
  const Result r = run(
      c.compose(0, {"up", "--no-build", "--exit-code-from", "supervisor", "--no-color"}), 300.0);
  ASSERT_EQ(r.code, 0) << r.output.substr(r.output.size() > 6000 ? r.output.size() - 6000 : 0);
  std::vector<std::filesystem::path> runs;
  for (const auto& e : std::filesystem::directory_iterator(c.dir_ / "runs")) runs.push_back(e);
  ASSERT_EQ(runs.size(), 1u);
  const records::Summary s = read_summary(runs[0]);
  EXPECT_TRUE(s.converged());
  EXPECT_EQ(s.agents_size(), kHosts * ComposeHosts::kReplicas);
  EXPECT_EQ(s.missing_agents_size(), 0);
  EXPECT_LT(s.average_relative_error(), 1e-9);
  // Each host flew its own replicas, whatever ids they claimed.
  std::map<std::string, int> per_host;
  for (const auto& a : s.agents()) {
    ASSERT_GT(a.hosts_size(), 0) << a.DebugString();
    const std::string& host = a.hosts(a.hosts_size() - 1);
    per_host[host.substr(host.find('/') + 1)]++;
  }
  for (int h = 0; h < kHosts; ++h)
    EXPECT_EQ(per_host[c.hosts_.address(h)], ComposeHosts::kReplicas) << "host " << h;
}

}  // namespace
}  // namespace qswarm::test
