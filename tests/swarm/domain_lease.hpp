#pragma once

#include <string>

namespace qswarm::test {

// A DDS domain this test process holds alone on this host: an exclusive flock on
// /tmp/qswarm-test-domains/D.lock for the lease's lifetime. Two ctest runs in different build
// directories (or the same one twice) at once never share a domain, whatever tests they run;
// the lock dies with the process, so a crashed test frees its domain. Candidates start at a hash
// of the test's name and skip domain 0 (a user's default) and the low ids.
class DomainLease {
 public:
  explicit DomainLease(const std::string& key);
  ~DomainLease();
  DomainLease(const DomainLease&) = delete;
  DomainLease& operator=(const DomainLease&) = delete;
  int domain() const { return domain_; }
  std::string str() const { return std::to_string(domain_); }

 private:
  int domain_ = -1;
  int fd_ = -1;
};

// The lease for the running gtest case (key: suite.name).
DomainLease& test_domain();

}  // namespace qswarm::test
