#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

namespace qswarm {

// What the launcher needs of its children, so that tests can stand in for real processes.
class ChildProcesses {
 public:
  struct Child {
    std::string role;  // "supervisor" or "agent"
    unsigned id = 0;
    pid_t pid = -1;
    bool running = false;
    int status = 0;                   // waitpid status once exited
    bool killed_at_teardown = false;  // needed SIGKILL after the grace period
  };
  virtual ~ChildProcesses() = default;
  // Starts argv[0] with the given arguments; stdout (and stderr unless keep_stderr) go to
  // `log_path` unless it is empty.
  virtual pid_t spawn(const std::string& role, unsigned id, const std::vector<std::string>& argv,
                      const std::string& log_path, bool keep_stderr = false) = 0;
  // Reaps exited children without blocking; returns those that exited in this call.
  virtual std::vector<Child> reap() = 0;
  // SIGTERM to all running children (supervisor first), wait up to grace_s, then SIGKILL the rest.
  // Returns how many needed SIGKILL.
  virtual int terminate_all(double grace_s) = 0;
  virtual const std::vector<Child>& children() const = 0;
  bool any_running() const;
};

// The launcher's children as real processes. Each child gets PR_SET_PDEATHSIG(SIGTERM), so it
// stops if the launcher dies. Teardown sends SIGTERM, waits a grace period, then escalates to
// SIGKILL, and reaps every child, so that nothing is left behind.
class ProcessGroup final : public ChildProcesses {
 public:
  ~ProcessGroup() override;
  pid_t spawn(const std::string& role, unsigned id, const std::vector<std::string>& argv,
              const std::string& log_path, bool keep_stderr = false) override;
  std::vector<Child> reap() override;
  int terminate_all(double grace_s) override;
  const std::vector<Child>& children() const override { return children_; }

 private:
  std::vector<Child> children_;
};

std::string describe_status(int status);

}  // namespace qswarm
