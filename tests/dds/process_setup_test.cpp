// An exception escaping a thread of an agent or supervisor (Fast DDS's threads included) ends the
// process with exit code 1 and a line naming it, not an abort the launcher can only call a signal.
#include <gtest/gtest.h>

#include <cerrno>
#include <new>
#include <stdexcept>
#include <string>
#include <system_error>
#include <thread>

#include "common/app/process_dds.hpp"
#include "common/app/process_life.hpp"
#include "common/dds/participant.hpp"

namespace qswarm {
namespace {

TEST(ProcessSetupDeathTest, AThreadOutOfResourcesExitsOneNamingIt) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        exit_cleanly_on_uncaught_exceptions("swarm-agent");
        std::thread([] {
          throw std::system_error(EAGAIN, std::generic_category(), "thread creation");
        }).join();
      },
      ::testing::ExitedWithCode(1),
      "swarm-agent: fatal: uncaught exception: thread creation: .*out of threads or memory");
}

TEST(ProcessSetupDeathTest, AnyOtherEscapedExceptionExitsOneWithItsMessage) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        exit_cleanly_on_uncaught_exceptions("swarm-supervisor");
        std::thread([] { throw std::runtime_error("boom"); }).join();
      },
      ::testing::ExitedWithCode(1), "swarm-supervisor: fatal: uncaught exception: boom");
}

TEST(ProcessSetup, AMainsLastCatchNamesRunningOutOfThreadsOrMemory) {
  const std::string hint = "out of threads or memory";
  EXPECT_NE(
      describe_exception(std::system_error(EAGAIN, std::generic_category(), "clone")).find(hint),
      std::string::npos);
  EXPECT_NE(describe_exception(std::system_error(ENOMEM, std::generic_category())).find(hint),
            std::string::npos);
  EXPECT_NE(describe_exception(std::bad_alloc()).find(hint), std::string::npos);
  EXPECT_EQ(describe_exception(std::system_error(EINVAL, std::generic_category(), "join")),
            "join: Invalid argument");
  EXPECT_EQ(describe_exception(std::runtime_error("dds: cannot create the state topic")),
            "dds: cannot create the state topic");
}

TEST(ProcessSetup, AListOfDiscoveryServersIsReadInOrderAndABadOneIsNamed) {
  const auto two = resolve_discovery_servers("10.0.1.2:11811,10.0.2.2:11812");
  ASSERT_EQ(two.size(), 2u);
  EXPECT_EQ(two[0], std::make_pair(std::string("10.0.1.2"), std::uint16_t{11811}));
  EXPECT_EQ(two[1], std::make_pair(std::string("10.0.2.2"), std::uint16_t{11812}));
  // Each entry's place is its GUID prefix on the wire: the clients' list and the servers' agree.
  eprosima::fastdds::rtps::RemoteServerList_t clients, server1;
  add_discovery_servers(two, -1, clients);
  add_discovery_servers(two, 1, server1);
  ASSERT_EQ(clients.size(), 2u);
  ASSERT_EQ(server1.size(), 1u);
  EXPECT_EQ(server1.front().guidPrefix, clients.front().guidPrefix);
  EXPECT_NE(clients.front().guidPrefix, clients.back().guidPrefix);
  for (const char* bad : {"10.0.1.2:11811,", ",10.0.1.2:11811", "10.0.1.2", "1.1.1.1:1,b:2:x",
                          "1.1.1.1:1,1.1.1.2:1,1.1.1.3:1,1.1.1.4:1,1.1.1.5:1", "1.2.3.4:0"}) {
    try {
      resolve_discovery_servers(bad);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("discovery server"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace qswarm
