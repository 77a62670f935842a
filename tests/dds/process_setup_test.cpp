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

}  // namespace
}  // namespace qswarm
