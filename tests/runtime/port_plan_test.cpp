// The port plan: a block of ports per domain, and a run's participant ids taken where the ports
// are free.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <thread>
#include <vector>

#include "common/transport/port_plan.hpp"

namespace qswarm {
namespace {

// Holds a UDP port on 127.0.0.1 as another program would.
class HeldPort {
 public:
  explicit HeldPort(std::uint32_t port) : fd_(::socket(AF_INET, SOCK_DGRAM, 0)) {
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<std::uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    held_ = ::bind(fd_, reinterpret_cast<const sockaddr*>(&a), sizeof a) == 0;
  }
  ~HeldPort() { ::close(fd_); }
  bool held() const { return held_; }

 private:
  int fd_;
  bool held_ = false;
};

TEST(PortPlan, EveryDomainHoldsTheLargestSwarmBelowTheEphemeralPorts) {
  EXPECT_EQ(PortPlan::discovery_port(0, 0), 7410u);  // Fast DDS's own first port on domain 0
  // 512 agents, the supervisor and the run's two Discovery Servers; or two runs of 256.
  EXPECT_GE(PortPlan::kMaxParticipantId + 1, 512 + 1 + 2);
  EXPECT_GE(PortPlan::kMaxParticipantId + 1, 2 * (256 + 1 + 2));
  // The last participant of a domain stays below the next domain's multicast port.
  EXPECT_LT(PortPlan::data_port(3, PortPlan::kMaxParticipantId), PortPlan::kBase + 4 * 1100u);
  // Below Linux's ephemeral ports (32768 up), which any socket bound to port 0 may take.
  EXPECT_LT(PortPlan::data_port(PortPlan::kMaxDomain, PortPlan::kMaxParticipantId), 32768u);
  EXPECT_NE(participant_ports_problem(PortPlan::kMaxDomain + 1, 0, "127.0.0.1"), "");
  EXPECT_NE(participant_ports_problem(0, 545, "127.0.0.1"), "");
}

TEST(PortPlan, UnicastPeersAreABlockOfIdsWithinThePlan) {
  std::string why;
  EXPECT_EQ(parse_unicast_peers("100:2", why), (std::pair{100, 2}));
  EXPECT_EQ(parse_unicast_peers("0:545", why), (std::pair{0, 545}));
  for (const char* bad :
       {"", "5", "5:", ":5", "5:0", "-1:3", "544:2", "1:2:3", "a:b", "3:2x", "99999999999:1"}) {
    EXPECT_FALSE(parse_unicast_peers(bad, why)) << bad;
    EXPECT_NE(why.find("FIRST:COUNT"), std::string::npos) << bad;
  }
}

TEST(PortPlan, ARunsBlockSkipsTakenPortsAndATakenIdIsNamed) {
  // Domain 19 is left to users by the tests' domain leases; ids from 480 are far from any run.
  const std::uint32_t domain = 19;
  ASSERT_EQ(participant_ports_problem(domain, 483, "127.0.0.1"), "") << "the port is in use here";
  EXPECT_FALSE(this_process_holds_udp_port(PortPlan::data_port(domain, 483)));
  const HeldPort other(PortPlan::data_port(domain, 483));
  ASSERT_TRUE(other.held());
  EXPECT_TRUE(this_process_holds_udp_port(PortPlan::data_port(domain, 483)));
  const std::string why = participant_ports_problem(domain, 483, "127.0.0.1");
  EXPECT_NE(why.find(std::to_string(PortPlan::data_port(domain, 483))), std::string::npos) << why;
  EXPECT_NE(why.find("another run on this domain"), std::string::npos) << why;
  EXPECT_EQ(free_participant_block(domain, 5, "127.0.0.1", 480), std::optional<int>(484));
  EXPECT_EQ(free_participant_block(domain, 100, "127.0.0.1", 480), std::nullopt);  // no room left
}

// Two launchers choosing at the same moment, before either run binds a port, still get blocks
// that do not overlap; a block held by a process that died is free again.
TEST(PortPlan, ReservationsMadeAtOnceNeverOverlapAndADeadHoldersBlockIsFreed) {
  const std::filesystem::path registry = std::filesystem::temp_directory_path() /
                                         ("qswarm-port-registry-" + std::to_string(::getpid()));
  std::filesystem::remove_all(registry);
  const std::uint32_t domain = 19;
  std::vector<std::optional<PortReservation>> held(8);
  std::vector<std::thread> launchers;
  for (std::size_t i = 0; i < held.size(); ++i)
    launchers.emplace_back([&, i] {
      if (auto r = PortReservation::reserve(domain, 20, "127.0.0.1", registry.string()))
        held[i].emplace(std::move(*r));
    });
  for (auto& t : launchers) t.join();
  std::vector<int> bases;
  for (const auto& h : held) {
    ASSERT_TRUE(h.has_value());
    bases.push_back(h->base());
  }
  std::sort(bases.begin(), bases.end());
  for (std::size_t i = 1; i < bases.size(); ++i) EXPECT_GE(bases[i], bases[i - 1] + 20);
  // The first block's holder goes; a stranger's file for a dead pid holds nothing.
  const int first = bases.front();
  for (auto& h : held)
    if (h && h->base() == first) h.reset();
  std::ofstream(registry / "domain-19-dead") << 999999999 << ' ' << first << ' ' << 20 << '\n';
  auto again = PortReservation::reserve(domain, 20, "127.0.0.1", registry.string());
  ASSERT_TRUE(again.has_value());
  EXPECT_EQ(again->base(), first);
  EXPECT_FALSE(std::filesystem::exists(registry / "domain-19-dead"));
  held.clear();
  again.reset();
  std::filesystem::remove_all(registry);
}

}  // namespace
}  // namespace qswarm
