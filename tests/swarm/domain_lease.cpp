#include "tests/swarm/domain_lease.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <unistd.h>

#include <filesystem>
#include <functional>
#include <memory>
#include <stdexcept>

namespace qswarm::test {
namespace {
// Leave 0..9 to users and hand-run scenarios; the port plan ends at 22 (PortPlan::kMaxDomain).
constexpr int kFirst = 10, kLast = 22;
}  // namespace

DomainLease::DomainLease(const std::string& key) {
  const std::filesystem::path dir = "/tmp/qswarm-test-domains";
  std::filesystem::create_directories(dir);
  const int span = kLast - kFirst + 1;
  const int start =
      static_cast<int>(std::hash<std::string>{}(key) % static_cast<std::size_t>(span));
  for (int k = 0; k < span; ++k) {
    const int d = kFirst + (start + k) % span;
    const std::string path = (dir / (std::to_string(d) + ".lock")).string();
    const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
    if (fd < 0) continue;
    if (::flock(fd, LOCK_EX | LOCK_NB) == 0) {
      domain_ = d;
      fd_ = fd;
      return;
    }
    ::close(fd);
  }
  throw std::runtime_error("no free DDS test domain in 10..22");
}

DomainLease::~DomainLease() {
  if (fd_ >= 0) ::close(fd_);
}

DomainLease& test_domain() {
  static std::unique_ptr<DomainLease> lease;
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string key = info ? std::string(info->test_suite_name()) + "." + info->name() : "?";
  if (!lease) lease = std::make_unique<DomainLease>(key);
  return *lease;
}

}  // namespace qswarm::test
