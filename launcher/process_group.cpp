#include "launcher/process_group.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <stdexcept>
#include <thread>

namespace qswarm {

ProcessGroup::~ProcessGroup() {
  if (any_running()) terminate_all(2.0);
}

pid_t ProcessGroup::spawn(const std::string& role, unsigned id,
                          const std::vector<std::string>& argv, const std::string& log_path,
                          bool keep_stderr) {
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
  if (pid == 0) {
    // A process group of its own: once the launcher is gone, the group is orphaned, and the kernel
    // sends a stopped member SIGHUP and SIGCONT (POSIX), so a child stopped (SIGSTOP, Ctrl-Z of its
    // own) when the launcher died wakes up to the SIGTERM below instead of staying stopped for
    // good. It also keeps a terminal's Ctrl-C to the launcher, which tears the run down in order.
    setpgid(0, 0);
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != parent) _exit(127);  // the launcher died before prctl took effect
    // Restore default dispositions the launcher may have changed.
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    signal(SIGHUP, SIG_DFL);
    if (!log_path.empty()) {
      const int fd = open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
      if (fd >= 0) {
        dup2(fd, STDOUT_FILENO);
        if (!keep_stderr) dup2(fd, STDERR_FILENO);
      }
    }
    std::vector<char*> args;
    args.reserve(argv.size() + 1);
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    std::fprintf(stderr, "exec %s: %s\n", args[0], std::strerror(errno));
    _exit(127);
  }
  setpgid(pid, pid);  // also from here, so the group exists whichever of the two runs first
  children_.push_back({role, id, pid, true, 0});
  return pid;
}

std::vector<ChildProcesses::Child> ProcessGroup::reap() {
  std::vector<Child> out;
  for (Child& c : children_) {
    if (!c.running) continue;
    int status = 0;
    const pid_t r = waitpid(c.pid, &status, WNOHANG);
    if (r == c.pid) {
      c.running = false;
      c.status = status;
      out.push_back(c);
    }
  }
  return out;
}

bool ChildProcesses::any_running() const {
  for (const Child& c : children())
    if (c.running) return true;
  return false;
}

int ProcessGroup::terminate_all(double grace_s) {
  // The supervisor first, so it records the agents' last states before they stop.
  for (const Child& c : children_)
    if (c.running && c.role == "supervisor") kill(c.pid, SIGTERM);
  for (const Child& c : children_)
    if (c.running && c.role != "supervisor") kill(c.pid, SIGTERM);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(grace_s);
  while (any_running() && std::chrono::steady_clock::now() < deadline) {
    reap();
    if (any_running()) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  int killed = 0;
  for (Child& c : children_) {
    if (!c.running) continue;
    kill(c.pid, SIGKILL);
    ++killed;
    c.killed_at_teardown = true;
    int status = 0;
    waitpid(c.pid, &status, 0);
    c.running = false;
    c.status = status;
  }
  return killed;
}

std::string describe_status(int status) {
  if (WIFEXITED(status)) return "exited with code " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) return std::string("killed by signal ") + strsignal(WTERMSIG(status));
  return "status " + std::to_string(status);
}

}  // namespace qswarm
