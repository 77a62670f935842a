// Peers that leave are forgotten at once, and no participant ever runs a lease check on a peer.
//
// Fast DDS 2.9.1 checks each remote participant's lease on its timer thread and removes a remote
// that leaves (its DISPOSE announcement) on a receive thread. When a lease check is already under
// way as the same remote is removed, it wakes on a cleared proxy and PDP.cpp:1140 asserts
// (Debian's build keeps asserts): the participant that stays aborts. That was "agent N killed by
// signal Aborted" at the teardown of 64-agent runs (the core: the assert on the timer thread,
// PDP::remove_remote_participant on a receive thread, the agent's own teardown on the main
// thread). DdsBus participants therefore announce an infinite lease: no lease check is ever
// scheduled, and a peer that leaves is still removed at once by its DISPOSE.
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <gtest/gtest.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

#include "common/dds/dds_bus.hpp"
#include "common/transport/port_plan.hpp"
#include "tests/swarm/domain_lease.hpp"
#include "tests/swarm/harness.hpp"

namespace qswarm {
namespace {

namespace dds = eprosima::fastdds::dds;

DdsOptions churn_options(const char* name) {
  DdsOptions o;
  o.participant.domain_id = static_cast<std::uint32_t>(test::test_domain().domain());
  o.state.max_agents = 64;
  o.state.run_id = 0xC4;
  o.participant.name = name;
  return o;
}

// A bare participant on loopback that notes the lease every discovered participant announces.
class LeaseWatcher : public dds::DomainParticipantListener {
 public:
  explicit LeaseWatcher(std::uint32_t domain) {
    dds::DomainParticipantQos q;
    q.name("lease-watcher");
    q.transport().use_builtin_transports = false;
    // The swarm's port plan: another domain gain would listen on another multicast port.
    q.wire_protocol().port.domainIDGain = PortPlan::kDomainGain;
    auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
    udp->interfaceWhiteList.push_back("127.0.0.1");
    q.transport().user_transports.push_back(udp);
    participant_ =
        dds::DomainParticipantFactory::get_instance()->create_participant(domain, q, this);
  }
  ~LeaseWatcher() override {
    if (participant_)
      dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
  }
  LeaseWatcher(const LeaseWatcher&) = delete;
  LeaseWatcher& operator=(const LeaseWatcher&) = delete;
  bool ok() const { return participant_ != nullptr; }
  void on_participant_discovery(
      dds::DomainParticipant*, eprosima::fastrtps::rtps::ParticipantDiscoveryInfo&& info) override {
    if (info.status != eprosima::fastrtps::rtps::ParticipantDiscoveryInfo::DISCOVERED_PARTICIPANT)
      return;
    std::lock_guard<std::mutex> lock(mu_);
    leases_[info.info.m_participantName.to_string()] = info.info.m_leaseDuration;
  }
  std::map<std::string, eprosima::fastrtps::Duration_t> leases() const {
    std::lock_guard<std::mutex> lock(mu_);
    return leases_;
  }

 private:
  dds::DomainParticipant* participant_ = nullptr;
  mutable std::mutex mu_;
  std::map<std::string, eprosima::fastrtps::Duration_t> leases_;
};

TEST(ParticipantChurn, EveryParticipantAnnouncesAnInfiniteLeaseSoNoPeerChecksIt) {
  LeaseWatcher watcher(static_cast<std::uint32_t>(test::test_domain().domain()));
  ASSERT_TRUE(watcher.ok());
  DdsBus bus(churn_options("an-agent"));
  ASSERT_TRUE(test::wait_for([&] { return watcher.leases().count("an-agent") == 1; }, 30.0));
  EXPECT_EQ(watcher.leases().at("an-agent"), eprosima::fastrtps::c_TimeInfinite);
}

TEST(ParticipantChurn, PeersLeavingInBurstsAreForgottenAtOnceAndTheOneThatStaysLives) {
  DdsBus stayer(churn_options("stayer"));
  const int own = 1;  // the stayer's writer matches its own reader
  ASSERT_TRUE(test::wait_for([&] { return stayer.matched_readers() == own; }, 30.0));
  const DdsOptions crowd_opts = churn_options("crowd");
  constexpr int kRounds = 6;
  constexpr int kCrowd = 16;
  for (int round = 0; round < kRounds; ++round) {
    std::vector<std::unique_ptr<DdsBus>> crowd;
    crowd.reserve(kCrowd);
    for (int k = 0; k < kCrowd; ++k) crowd.push_back(std::make_unique<DdsBus>(crowd_opts));
    ASSERT_TRUE(test::wait_for([&] { return stayer.matched_readers() == own + kCrowd; }, 30.0))
        << "round " << round << ": " << stayer.matched_readers() - own << " of " << kCrowd;
    crowd.clear();  // kCrowd DISPOSE announcements at once
    // No lease is left to expire: only the DISPOSE can remove them.
    ASSERT_TRUE(test::wait_for([&] { return stayer.matched_readers() == own; }, 30.0))
        << "round " << round << ": " << stayer.matched_readers() - own << " readers left";
  }
}

// A participant takes the ports the plan gives its id, or refuses to start naming the port: two
// processes given the same id (or another program on its port) never leave one of them deaf.
TEST(ParticipantPorts, AnExplicitIdHoldsItsPortsAndASecondOneOnThemIsRefusedNamingThePort) {
  ParticipantOptions o;
  o.domain_id = static_cast<std::uint32_t>(test::test_domain().domain());
  o.participant_id = 530;
  o.name = "ports-first";
  const DdsParticipant first(o);
  EXPECT_NE(participant_ports_problem(o.domain_id, 530, o.interface), "");
  o.name = "ports-second";
  try {
    const DdsParticipant second(o);
    FAIL() << "a second participant came up on the ports of the first";
  } catch (const std::runtime_error& e) {
    const std::string port = std::to_string(PortPlan::discovery_port(o.domain_id, 530));
    EXPECT_NE(std::string(e.what()).find(port), std::string::npos) << e.what();
  }
}

// The nice value of each of this process's threads (/proc/self/task/*/stat, field 19). A thread
// that ended after the directory was listed (the participant's helper, joined a moment ago, can
// still be listed) has no stat to read any more: it is left out.
std::map<int, int> thread_nice_values() {
  std::map<int, int> out;
  for (const auto& t : std::filesystem::directory_iterator("/proc/self/task")) {
    std::ifstream stat(t.path() / "stat");
    std::string line;
    if (!std::getline(stat, line)) continue;
    const auto paren = line.rfind(')');
    if (paren == std::string::npos || paren + 2 > line.size()) continue;
    std::istringstream rest(line.substr(paren + 2));  // after "pid (comm) "
    std::string field;
    int i = 3;
    for (; i <= 19 && rest >> field; ++i) {
    }
    if (i <= 19) continue;
    out[std::stoi(t.path().filename().string())] = std::stoi(field);
  }
  return out;
}

// What a participant made with `threads_nice` did to the nice values of the threads it started
// and of the thread that made it, and what it said.
struct StartedThreads {
  int self = 0, self_after = 0;
  std::vector<int> nice;  // of each thread it started
  std::string said;       // DdsParticipant::threads_priority()
};
StartedThreads start_threads(int threads_nice, const char* name) {
  const std::map<int, int> before = thread_nice_values();
  StartedThreads s;
  s.self = before.at(static_cast<int>(::gettid()));
  ParticipantOptions o;
  o.domain_id = static_cast<std::uint32_t>(test::test_domain().domain());
  o.name = name;
  o.threads_nice = threads_nice;
  const DdsParticipant p(o);
  s.said = p.threads_priority();
  for (const auto& [tid, nice] : thread_nice_values())
    if (!before.count(tid)) s.nice.push_back(nice);
  s.self_after = thread_nice_values().at(static_cast<int>(::gettid()));
  return s;
}

// An agent's tick goes first when the CPU is short: the threads Fast DDS starts run nicer, and
// the thread that created the participant keeps its priority.
TEST(ParticipantThreads, FastDdsThreadsRunNicerThanTheThreadThatCreatedThem) {
  const StartedThreads s = start_threads(3, "nicer-threads");
  const int want = std::min(s.self + 3, 19);
  EXPECT_GE(s.nice.size(), 2u);  // at least a receive thread and the event thread
  for (const int nice : s.nice) EXPECT_EQ(nice, want);
  EXPECT_EQ(s.said, "nice " + std::to_string(want) + " (was " + std::to_string(s.self) + ")");
  EXPECT_EQ(s.self_after, s.self);
}

// Asked to run ahead of the thread that made them, Fast DDS's threads do where the host allows
// it, and the participant says which it was.
// Whether the kernel lets this thread raise its priority by `by` (root, or RLIMIT_NICE), asked in
// a child process so that nothing here changes: the test's own answer, not the product's.
bool host_allows_raising(int by) {
  const pid_t child = ::fork();
  if (child == 0) {
    errno = 0;
    const int r = ::nice(-by);
    ::_exit(r == -1 && errno != 0 ? 1 : 0);
  }
  int status = 0;
  return child > 0 && ::waitpid(child, &status, 0) == child && WIFEXITED(status) &&
         WEXITSTATUS(status) == 0;
}

TEST(ParticipantThreads, FastDdsThreadsRunAheadWhereTheHostAllowsItAndSaySo) {
  const bool allowed = host_allows_raising(3);
  const StartedThreads s = start_threads(-3, "keener-threads");
  const int want = allowed ? std::max(s.self - 3, -20) : s.self;
  if (allowed)
    EXPECT_EQ(s.said, "nice " + std::to_string(want) + " (was " + std::to_string(s.self) + ")");
  else
    EXPECT_NE(s.said.find("cannot"), std::string::npos) << s.said;
  EXPECT_GE(s.nice.size(), 2u);
  for (const int nice : s.nice) EXPECT_EQ(nice, want) << s.said;
  EXPECT_EQ(s.self_after, s.self);
}

}  // namespace
}  // namespace qswarm
