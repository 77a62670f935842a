#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

namespace qswarm {

// The launcher's children. Each child gets PR_SET_PDEATHSIG(SIGTERM), so it stops if the launcher
// dies. Teardown sends SIGTERM, waits a grace period, then escalates to SIGKILL, and reaps
// every child, so that nothing is left behind.
class ProcessGroup {
 public:
  struct Child {
    std::string role;  // "supervisor" or "agent"
    unsigned id = 0;
    pid_t pid = -1;
    bool running = false;
    int status = 0;  // waitpid status once exited
  };

  ~ProcessGroup();
  // Starts argv[0] with the given arguments; stdout/stderr go to `log_path` unless empty.
  pid_t spawn(const std::string& role, unsigned id, const std::vector<std::string>& argv,
              const std::string& log_path);
  // Reaps exited children without blocking; returns those that exited in this call.
  std::vector<Child> reap();
  // SIGTERM to all running children (supervisor first), wait up to grace_s, then SIGKILL the rest.
  // Returns how many needed SIGKILL.
  int terminate_all(double grace_s);
  const std::vector<Child>& children() const { return children_; }
  bool any_running() const;

 private:
  std::vector<Child> children_;
};

std::string describe_status(int status);

}  // namespace qswarm
