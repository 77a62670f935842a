// Attacks on a run made as a stranger on its network would make them: qswarm-attacker
// (tests/attacker/attacker.cpp) learns the run id from the wildcard partition qswarm-run-*, then
// relays or impersonates an agent. A plain run cannot prevent it and must name it (and never lock
// the real agent out); a secure run must refuse it. Every run is faults_six (edge-flow, six agents
// on the complete graph: the agreed value must stay the initial average (14, 9, 20) to 1e-8 m),
// flown by `swarm run` exactly as a user would, with the attacker on the same leased domain.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <linux/if_packet.h>
#include <net/ethernet.h>
#include <net/if.h>
#include <netinet/ip.h>
#include <netinet/udp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "common/scenario/scenario.hpp"
#include "common/transport/port_plan.hpp"
#include "tests/support/cannot_run.hpp"
#include "tests/swarm/domain_lease.hpp"
#include "tests/swarm/harness.hpp"

namespace qswarm::test {
namespace {

namespace fs = std::filesystem;
const Vec3 kAgreement(14, 9, 20);  // faults_six's initial average

std::map<std::string, std::string> read_report(const fs::path& p) {
  std::map<std::string, std::string> out;
  std::ifstream in(p);
  for (std::string line; std::getline(in, line);) {
    const auto eq = line.find('=');
    if (eq != std::string::npos) out[line.substr(0, eq)] = line.substr(eq + 1);
  }
  return out;
}

// Where a secure run's processes discover each other (by unicast only): the first participant ids
// of the port plan on the test's own domain, where the launcher reserves the run's block.
constexpr const char* kSecureBlock = "0:32";

struct Attacker {
  Attacker(const std::string& name, const fs::path& dir, std::vector<std::string> args)
      : report(dir.parent_path() / (name + "-attacker.txt")),
        child(argv(report, std::move(args)), dir.parent_path() / (name + "-attacker.log")) {}
  static std::vector<std::string> argv(const fs::path& report, std::vector<std::string> args) {
    fs::remove(report);
    std::vector<std::string> a = {bin("qswarm-attacker"), "--domain", test_domain().str(),
                                  "--report", report.string()};
    a.insert(a.end(), args.begin(), args.end());
    return a;
  }
  // Stops it (if still attacking) and reads what it did.
  std::map<std::string, std::string> finish(int* code = nullptr) {
    if (child.running()) child.signal(SIGTERM);
    const Result r = child.wait(30.0);
    if (code) *code = r.code;
    log = r.output;
    return read_report(report);
  }
  fs::path report;
  Child child;
  std::string log;
};

std::vector<std::string> run_argv(const fs::path& dir, const std::vector<std::string>& extra,
                                  const std::string& duration_s = "60") {
  std::vector<std::string> a = {bin("swarm"), "run",      scenario("faults_six"), "--out",
                                dir.string(), "--domain", test_domain().str(),    "--quiet",
                                "--duration", duration_s};
  a.insert(a.end(), extra.begin(), extra.end());
  return a;
}

// A keystore for faults_six, made by the product's `swarm keys`.
fs::path keystore(const std::string& name) {
  const fs::path ks = fresh_dir(name + "-keys");
  const Result r = run({bin("swarm"), "keys", scenario("faults_six"), "--out", ks.string()}, 60.0);
  EXPECT_EQ(r.code, 0) << r.output;
  return ks;
}

// Who noticed agent `id`'s samples forged as `kind` (0: the supervisor); empty: not named.
std::set<unsigned> noticed(const records::Summary& s, unsigned id, const std::string& kind) {
  std::set<unsigned> by;
  for (const auto& f : s.forgeries())
    if (f.agent() == id && f.kind() == kind)
      by.insert(f.noticed_by().begin(), f.noticed_by().end());
  return by;
}

Vec3 final_q(const records::Summary& s, unsigned id) {
  for (const auto& a : s.agents())
    if (a.id() == id && a.final_consensus_size() == 3)
      return Vec3(a.final_consensus(0), a.final_consensus(1), a.final_consensus(2));
  return Vec3::Constant(1e9);
}

int files_containing(const fs::path& dir, const std::string& prefix, const std::string& text) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string f = e.path().filename().string();
    if (f.rfind(prefix, 0) == 0 && read_file(e.path()).find(text) != std::string::npos) ++n;
  }
  return n;
}

std::string drift_line(const records::Summary& s) {
  return "final mean " + std::to_string(s.final_consensus_mean(0)) + ", " +
         std::to_string(s.final_consensus_mean(1)) + ", " +
         std::to_string(s.final_consensus_mean(2)) + "; drift " +
         std::to_string(s.average_drift_m()) + " m";
}

// (a) The forged-flow relay: agent 1's real samples, a million sequence numbers ahead, its state
// and owned flows shifted 50 m. The agents keep the real agent 1 (the first writer, still
// speaking) and refuse the relay, name it, and the run that agreed does not say "converged".
TEST(Attack, APlainRunUnderTheForgedFlowRelayNamesItAndDoesNotConverge) {
  const fs::path dir = fresh_dir("attack-relay");
  Attacker attacker("attack-relay", dir,
                    {"--mode", "relay", "--victim", "1", "--streams", "state"});
  const Result r = run(run_argv(dir, {}), 240.0);
  const auto report = attacker.finish();
  EXPECT_EQ(report.at("learned").rfind("wildcard", 0), 0u) << attacker.log;
  EXPECT_GT(std::stoull(report.at("published")), 50u) << attacker.log;
  ASSERT_EQ(r.code, 1) << r.output;
  const records::Summary s = read_summary(dir);
  RecordProperty("drift", drift_line(s));
  EXPECT_FALSE(s.converged());
  EXPECT_NE(s.end_reason().find("agent 1 came from two writers"), std::string::npos)
      << s.end_reason();
  EXPECT_GE(noticed(s, 1, "two_writers").size(), 3u);
  EXPECT_GE(noticed(s, 1, "sequence_jump").size(), 3u);
  EXPECT_TRUE(s.missing_agents().empty());
  // Named in the agents' logs, the supervisor's, and events.csv.
  EXPECT_GE(files_containing(dir, "agent-", "agent 1: its samples came from two writers"), 3);
  EXPECT_EQ(files_containing(dir, "supervisor.log", "two_writers"), 1);
  int events = 0;
  for (const auto& row : read_csv(dir / "events.csv"))
    events += row.at("kind") == "forgery" && row.at("agent") == "1" ? 1 : 0;
  EXPECT_EQ(events, 2);  // two_writers and sequence_jump, once each
  // The relay was refused: the agreement did not move.
  EXPECT_LT(s.average_drift_m(), 1e-6) << drift_line(s);
}

// The same relay sending four copies of each real sample outpaces agent 1 and takes it over: a
// plain run cannot prevent that. The swarm follows the forged flows about 42 m away, and either
// agrees there (edge-flow's own check: "agreed X m from the initial average", which the law keeps)
// or, jostled by the relay, never agrees to 1e-8 m before the duration. Either way it is not
// converged, the two writers are named, and the summary says how far the mean moved.
TEST(Attack, AnOutpacingRelayMovesAPlainRunAndTheRecordSaysHowFar) {
  const fs::path dir = fresh_dir("attack-relay4");
  Attacker attacker("attack-relay4", dir,
                    {"--mode", "relay", "--victim", "1", "--streams", "state", "--copies", "4"});
  const Result r = run(run_argv(dir, {}, "20"), 240.0);
  attacker.finish();
  ASSERT_EQ(r.code, 1) << r.output;
  const records::Summary s = read_summary(dir);
  RecordProperty("drift", drift_line(s));
  EXPECT_FALSE(s.converged());
  EXPECT_GE(noticed(s, 1, "two_writers").size(), 3u);
  EXPECT_GT(s.average_drift_m(), 1.0) << drift_line(s);
  if (s.has_agreed_elsewhere_m()) {
    EXPECT_EQ(s.end_reason().rfind("agreed ", 0), 0u) << s.end_reason();
  } else {
    EXPECT_EQ(s.end_reason(), "duration");
  }
}

// (b) Impersonation: agent 3's samples, shifted 50 m, with a newer start time, at four times the
// agent's rate (so that the forger takes agent 3 over wherever the real one falls silent for
// three of its samples), for 8 s, then nothing. Named, and once the forger stops the real agent
// 3 is heard again by every agent and the supervisor: it is not missing, and the run agrees.
TEST(Attack, APlainRunUnderImpersonationNamesItAndHearsTheRealAgentAgainOnceTheForgerStops) {
  const fs::path dir = fresh_dir("attack-impersonate");
  Attacker attacker("attack-impersonate", dir,
                    {"--mode", "impersonate", "--victim", "3", "--rate", "200", "--for", "8"});
  const Result r = run(run_argv(dir, {}), 240.0);
  const auto report = attacker.finish();
  EXPECT_EQ(report.at("learned").rfind("wildcard", 0), 0u) << attacker.log;
  EXPECT_GT(std::stoull(report.at("published")), 1000u) << attacker.log;
  ASSERT_EQ(r.code, 1) << r.output;
  const records::Summary s = read_summary(dir);
  RecordProperty("drift", drift_line(s));
  EXPECT_FALSE(s.converged());
  EXPECT_EQ(s.end_reason().rfind("agreed, but the samples of agent 3 came from two writers", 0), 0u)
      << s.end_reason();
  EXPECT_TRUE(noticed(s, 3, "two_writers").count(0)) << "the supervisor";
  EXPECT_GE(noticed(s, 3, "two_writers").size(), 4u);
  // Heard again: the forger took agent 3 over (the supervisor's stream and the agents'), and lost
  // it to the real one once it stopped; agent 3 was not missing, and it ended at the agreement,
  // not at the forger's +50 m.
  EXPECT_TRUE(s.missing_agents().empty());
  EXPECT_EQ(files_containing(dir, "supervisor.log", "agent 3: now heard from writer"), 1);
  EXPECT_GE(files_containing(dir, "agent-", "agent 3: now heard from writer"), 3);
  EXPECT_LT((final_q(s, 3) - kAgreement).norm(), 1e-6) << final_q(s, 3).transpose();
  EXPECT_LT(s.final_disagreement_m(), 1e-6);
}

// (c) A stranger without credentials against a secure run: it learns nothing from the wildcard
// (discovery and samples are encrypted). Then a second one, told the run id (as if it leaked),
// publishes as agent 3 at 200 Hz on both streams: nothing reaches anyone, the run converges at the
// initial average and names no forgery. (One after the other: two strangers hear each other.) At
// a quarter of real time, so that the run still flies when the second one comes.
TEST(Attack, ASecureRunHearsNothingFromAStrangerWithoutCredentials) {
  const fs::path ks = keystore("attack-stranger");
  const fs::path dir = fresh_dir("attack-stranger");
  // A secure run discovers by unicast within its block (the launcher's, from id 0 on this leased
  // domain): the strangers announce to it there, as an attacker who scanned the ports would.
  Attacker learner("attack-stranger-learner", dir,
                   {"--mode", "impersonate", "--victim", "3", "--learn-timeout", "10",
                    "--unicast-peers", kSecureBlock});
  Child launcher(run_argv(dir, {"--secure", ks.string(), "--time-scale", "0.25"}),
                 dir.parent_path() / "attack-stranger.log");
  int learner_code = -1;
  ASSERT_TRUE(wait_for([&] { return !learner.child.running(); }, 60.0));
  const auto learned = learner.finish(&learner_code);
  EXPECT_EQ(learner_code, 3) << learner.log;
  EXPECT_EQ(learned.at("learned"), "none");
  EXPECT_EQ(learned.at("heard"), "0");
  ASSERT_TRUE(launcher.running()) << "the run ended before the second stranger came";
  const std::uint64_t run_id = load_scenario((dir / "scenario.txtpb").string()).transport.run_id;
  char hex[24];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(run_id));
  Attacker told("attack-stranger-told", dir,
                {"--mode", "impersonate", "--victim", "3", "--rate", "200", "--run-id", hex,
                 "--unicast-peers", kSecureBlock});
  const Result r = launcher.wait(240.0);
  const auto forged = told.finish();
  EXPECT_EQ(forged.at("heard"), "0") << told.log;
  EXPECT_GT(std::stoull(forged.at("published")), 500u) << told.log;
  ASSERT_EQ(r.code, 0) << r.output;
  const records::Summary s = read_summary(dir);
  RecordProperty("drift", drift_line(s));
  EXPECT_TRUE(s.secure());
  EXPECT_TRUE(s.converged());
  EXPECT_EQ(s.forgeries_size(), 0);
  EXPECT_LT(s.average_drift_m(), 1e-8);
  EXPECT_LT((final_q(s, 3) - kAgreement).norm(), 1e-6);
}

// (d) A member holding agent 3's certificate (stolen, or a compromised agent) learns the run id
// as a member does and publishes as agent 5 on both streams: its writers can only be in agent 3's
// partitions, so every agent and the supervisor refuse the samples and name them; the run
// converges at the initial average.
TEST(Attack, ASecureRunRefusesAMemberWithAgent3sCertificatePublishingAsAgent5) {
  const fs::path ks = keystore("attack-member");
  const fs::path dir = fresh_dir("attack-member");
  Attacker attacker("attack-member", dir,
                    {"--mode", "impersonate", "--as", "5", "--rate", "200", "--keystore",
                     ks.string(), "--identity", "agent-3", "--unicast-peers", kSecureBlock});
  const Result r = run(run_argv(dir, {"--secure", ks.string()}), 240.0);
  const auto report = attacker.finish();
  EXPECT_EQ(report.at("learned").rfind("wildcard", 0), 0u) << attacker.log;
  EXPECT_GT(std::stoull(report.at("published")), 500u) << attacker.log;
  ASSERT_EQ(r.code, 0) << r.output;
  const records::Summary s = read_summary(dir);
  RecordProperty("drift", drift_line(s));
  EXPECT_TRUE(s.converged());
  EXPECT_LT(s.average_drift_m(), 1e-8);
  EXPECT_TRUE(noticed(s, 5, "bound_elsewhere").count(0)) << "the supervisor";
  EXPECT_GE(noticed(s, 5, "bound_elsewhere").size(), 4u);
  EXPECT_TRUE(noticed(s, 5, "two_writers").empty());
  EXPECT_LT((final_q(s, 5) - kAgreement).norm(), 1e-6);
  EXPECT_GE(files_containing(dir, "agent-", "refused samples keyed as agent 5"), 4);
}

// The six agents of the fault runs with `extra` appended, flown secure with a keystore made for
// them: the run's directory and what `swarm keys` (if it failed) or `swarm run` said.
struct SecureSix {
  fs::path dir;
  Result result;
};
SecureSix fly_secure_six(const std::string& name, const std::string& extra) {
  SecureSix six{fresh_dir(name), {}};
  const fs::path scen = six.dir.parent_path() / (name + ".txtpb");
  std::ofstream(scen) << read_file(scenario("faults_six")) << extra;
  const fs::path ks = fresh_dir(name + "-keys");
  six.result = run({bin("swarm"), "keys", scen.string(), "--out", ks.string()}, 60.0);
  if (six.result.code == 0)
    six.result = run({bin("swarm"), "run", scen.string(), "--out", six.dir.string(), "--domain",
                      test_domain().str(), "--quiet", "--secure", ks.string()},
                     240.0);
  return six;
}

// A secure run's processes discover by unicast within the run's block: an agent killed (SIGKILL)
// and started again on its own participant id, and an agent that joins late, still meet every
// other one (a new participant each, a fresh key exchange), and the average holds.
TEST(SecureRun, AKilledAndRestartedAgentAndALateJoinerMeetEveryoneAgainAndTheAverageHolds) {
  const SecureSix six = fly_secure_six("secure-kill",
                                       "faults { kill { agent: 2 at_s: 3 restart_at_s: 6 } "
                                       "late_join { agent: 6 at_s: 2 } }\n");
  ASSERT_EQ(six.result.code, 0) << six.result.output;
  const records::Summary s = read_summary(six.dir);
  EXPECT_TRUE(s.secure());
  EXPECT_TRUE(s.converged()) << s.end_reason();
  EXPECT_EQ(s.agents_size(), 6);
  EXPECT_EQ(s.faults().kills(), 1u);
  EXPECT_EQ(s.faults().restarts(), 1u);
  EXPECT_EQ(s.faults().late_joins(), 1u);
  EXPECT_LT(s.average_relative_error(), 1e-9);
  EXPECT_LT((final_q(s, 2) - kAgreement).norm(), 1e-6);
  EXPECT_LT((final_q(s, 6) - kAgreement).norm(), 1e-6);
}

// DDS-Security over the receive at the tick, and over Fast DDS's receive threads: the
// handshakes, key exchange and encrypted samples pass through either, and the secure swarm meets
// at the exact average.
TEST(SecureRun, AgentsReceivingAtTheTickOrOnThreadsAuthenticateAndMeet) {
  for (const char* receive : {"TICK", "THREADS"}) {
    const SecureSix six = fly_secure_six(std::string("secure-") + receive,
                                         std::string("transport { receive: ") + receive + " }\n");
    ASSERT_EQ(six.result.code, 0) << receive << ": " << six.result.output;
    const records::Summary s = read_summary(six.dir);
    EXPECT_TRUE(s.secure()) << receive;
    EXPECT_TRUE(s.converged()) << receive << ": " << s.end_reason();
    EXPECT_LT(s.average_relative_error(), 1e-9) << receive;
    // Drained at the tick, or never (no counts written).
    for (unsigned id = 1; id <= 6; ++id)
      EXPECT_EQ(stats_value(six.dir, id, "tick_datagrams") > 0, std::string(receive) == "TICK")
          << receive << ", agent " << id;
  }
}

// Every UDP datagram to a domain's ports on loopback, as a root process sees them (an AF_PACKET
// socket on lo): what an attacker on the host, or on the radio link, captures.
class LoopbackCapture {
 public:
  struct Datagram {
    double t_s;  // since the capture started
    std::uint16_t port;
    std::string payload;
  };
  explicit LoopbackCapture(int domain)
      : lo_(PortPlan::kBase + PortPlan::kDomainGain * static_cast<std::uint32_t>(domain)),
        hi_(lo_ + PortPlan::kDomainGain) {
    fd_ = ::socket(AF_PACKET, SOCK_DGRAM, htons(ETH_P_IP));
    if (fd_ < 0) return;
    sockaddr_ll at{};
    at.sll_family = AF_PACKET;
    at.sll_protocol = htons(ETH_P_IP);
    at.sll_ifindex = static_cast<int>(if_nametoindex("lo"));
    if (::bind(fd_, reinterpret_cast<sockaddr*>(&at), sizeof at) != 0) {
      ::close(fd_);
      fd_ = -1;
      return;
    }
    thread_ = std::thread([this] { loop(); });
  }
  ~LoopbackCapture() { stop(); }
  bool ok() const { return fd_ >= 0; }
  std::vector<Datagram> stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    return std::move(got_);
  }

 private:
  void loop() {
    const auto start = std::chrono::steady_clock::now();
    std::vector<char> buf(65536);
    while (!stop_) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) continue;
      sockaddr_ll from{};
      socklen_t len = sizeof from;
      const ssize_t n =
          ::recvfrom(fd_, buf.data(), buf.size(), 0, reinterpret_cast<sockaddr*>(&from), &len);
      // Loopback shows each datagram leaving and arriving: keep the arrivals.
      if (n < static_cast<ssize_t>(sizeof(iphdr)) || from.sll_pkttype == PACKET_OUTGOING) continue;
      const auto* ip = reinterpret_cast<const iphdr*>(buf.data());
      const std::size_t ihl = ip->ihl * 4u;
      if (ip->protocol != IPPROTO_UDP || n < static_cast<ssize_t>(ihl + sizeof(udphdr))) continue;
      const auto* udp = reinterpret_cast<const udphdr*>(buf.data() + ihl);
      const std::uint16_t port = ntohs(udp->dest);
      if (port < lo_ || port >= hi_) continue;
      const std::size_t at = ihl + sizeof(udphdr);
      got_.push_back(
          {std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), port,
           std::string(buf.data() + at, static_cast<std::size_t>(n) - at)});
    }
  }
  std::uint32_t lo_, hi_;
  int fd_ = -1;
  std::atomic<bool> stop_{false};
  std::thread thread_;
  std::vector<Datagram> got_;
};

// An RTPS message without its INFO_DST submessages: addressed to no participant in particular, so
// that participants with other GUID prefixes than the captured run's take it too (a replay as is
// would reach no one: Fast DDS addresses most submessages to the receiver's GUID prefix, and a
// later run's participants have new ones). Under DDS-Security the submessages are inside the
// encrypted message, out of the attacker's reach: this changes nothing there.
std::string without_info_dst(const std::string& m) {
  constexpr std::size_t kHeader = 20;  // "RTPS", version, vendor, GUID prefix
  if (m.size() < kHeader || m.compare(0, 4, "RTPS") != 0) return m;
  std::string out = m.substr(0, kHeader);
  std::size_t at = kHeader;
  while (at + 4 <= m.size()) {
    const auto id = static_cast<unsigned char>(m[at]);
    const bool little = (static_cast<unsigned char>(m[at + 1]) & 1) != 0;
    const auto b0 = static_cast<unsigned char>(m[at + 2]),
               b1 = static_cast<unsigned char>(m[at + 3]);
    std::size_t len = little ? (b0 | (b1 << 8)) : ((b0 << 8) | b1);
    if (len == 0) len = m.size() - at - 4;  // the last submessage runs to the end
    const std::size_t end = std::min(m.size(), at + 4 + len);
    if (id != 0x0e) out.append(m, at, end - at);  // 0x0e: INFO_DST
    at = end;
  }
  return out;
}

// Sends captured datagrams back to 127.0.0.1 at their ports (multicast ones too: the participants'
// multicast sockets are bound to the port on every address), paced as captured, over and over
// until stopped. Counts what it sent.
class Replay {
 public:
  explicit Replay(std::vector<LoopbackCapture::Datagram> d) : d_(std::move(d)) {
    thread_ = std::thread([this] { loop(); });
  }
  ~Replay() { stop(); }
  std::uint64_t stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    return sent_;
  }

 private:
  void loop() {
    const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
    if (fd < 0 || d_.empty()) return;
    while (!stop_) {
      const auto start = std::chrono::steady_clock::now();
      for (const auto& g : d_) {
        if (stop_) break;
        std::this_thread::sleep_until(start + std::chrono::duration<double>(g.t_s));
        sockaddr_in to{};
        to.sin_family = AF_INET;
        to.sin_port = htons(g.port);
        to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        const std::string m = without_info_dst(g.payload);
        if (::sendto(fd, m.data(), m.size(), 0, reinterpret_cast<sockaddr*>(&to), sizeof to) > 0)
          ++sent_;
      }
    }
    ::close(fd);
  }
  std::vector<LoopbackCapture::Datagram> d_;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> sent_{0};
  std::thread thread_;
};

// Replay: a run's traffic captured on loopback, readdressed to anyone (without_info_dst) and
// replayed into a later run of the same scenario on the same domain (the same participant ids, so
// the same ports). Without security the replay reaches the later run: its supervisor matches the
// replayed writers and hears the earlier run's samples, which it refuses as another run's. With
// security the earlier run's sessions are gone: the replayed participants never authenticate,
// nothing they sent is decrypted, and the later run hears none of it, converges at the initial
// average and names nothing.
TEST(Attack, ARunsCapturedTrafficReplayedIntoALaterSecureRunReachesNoOne) {
  if (geteuid() != 0) QSWARM_CANNOT_RUN("needs root to capture loopback traffic (AF_PACKET)");
  const fs::path ks = keystore("attack-replay");
  const auto replayed_into = [&](const std::string& name, const std::vector<std::string>& extra,
                                 std::uint64_t* sent, std::size_t* captured) {
    LoopbackCapture capture(test_domain().domain());
    if (!capture.ok()) return records::Summary();
    const fs::path first = fresh_dir(name + "-captured");
    const Result r1 = run(run_argv(first, extra), 240.0);
    EXPECT_EQ(r1.code, 0) << r1.output;
    std::vector<LoopbackCapture::Datagram> got = capture.stop();
    *captured = got.size();
    const fs::path later = fresh_dir(name + "-later");
    Replay replay(std::move(got));
    std::vector<std::string> slow = extra;
    slow.insert(slow.end(), {"--time-scale", "0.5"});
    const Result r2 = run(run_argv(later, slow), 240.0);
    *sent = replay.stop();
    EXPECT_EQ(r2.code, 0) << r2.output;
    return read_summary(later);
  };
  std::uint64_t sent = 0;
  std::size_t captured = 0;
  // Plain: the replay reaches the later run.
  const records::Summary plain = replayed_into("attack-replay-plain", {}, &sent, &captured);
  if (captured == 0) QSWARM_CANNOT_RUN("cannot capture on lo here");
  EXPECT_GT(sent, 1000u);
  EXPECT_GT(plain.foreign_samples(), 0u) << "the replay never reached the later plain run";
  RecordProperty("plain", "captured " + std::to_string(captured) + ", replayed " +
                              std::to_string(sent) + ", foreign samples " +
                              std::to_string(plain.foreign_samples()));
  // Secure: it reaches no one.
  const records::Summary secure =
      replayed_into("attack-replay-secure", {"--secure", ks.string()}, &sent, &captured);
  EXPECT_GT(captured, 1000u);
  EXPECT_GT(sent, 1000u);
  RecordProperty("secure", "captured " + std::to_string(captured) + ", replayed " +
                               std::to_string(sent) + ", foreign samples " +
                               std::to_string(secure.foreign_samples()));
  EXPECT_TRUE(secure.converged());
  EXPECT_EQ(secure.foreign_samples(), 0u);
  EXPECT_EQ(secure.forgeries_size(), 0);
  EXPECT_LT(secure.average_drift_m(), 1e-8);
}

}  // namespace
}  // namespace qswarm::test
