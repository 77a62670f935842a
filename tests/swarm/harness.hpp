#pragma once

// Multi-process test harness: run the project's binaries as a user would, own their processes,
// wait on conditions (files appearing, processes exiting), never on fixed sleeps.
#include <signal.h>
#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "proto/records.pb.h"

namespace qswarm::test {

std::string bin(const std::string& name);
std::string scenario(const std::string& name);
// A fresh directory for a test's run (removed first if present).
std::filesystem::path fresh_dir(const std::string& name);
// The same path, without clearing it.
std::filesystem::path fresh_dir_path(const std::string& name);

struct Result {
  int code = -1;       // exit code, or 128 + signal
  std::string output;  // stdout and stderr together
};

// A child process with its output captured to a file.
class Child {
 public:
  explicit Child(const std::vector<std::string>& argv, const std::filesystem::path& log);
  ~Child();
  pid_t pid() const { return pid_; }
  bool running();
  // Waits for exit up to timeout_s (then SIGKILLs it and fails the wait).
  Result wait(double timeout_s);
  void signal(int sig) { ::kill(pid_, sig); }

 private:
  pid_t pid_ = -1;
  std::filesystem::path log_;
  bool done_ = false;
  int code_ = -1;
};

Result run(const std::vector<std::string>& argv, double timeout_s = 120.0);

// Polls `cond` every 20 ms until true or timeout; returns whether it became true.
bool wait_for(const std::function<bool()>& cond, double timeout_s);

records::Summary read_summary(const std::filesystem::path& run_dir);
std::string read_file(const std::filesystem::path& p);
// A number an agent wrote to its agent-ID.stats ("key value" lines); -1 if it wrote none.
double stats_value(const std::filesystem::path& run_dir, unsigned id, const std::string& key);
// Rows of a CSV file as column-name -> value maps.
std::vector<std::map<std::string, std::string>> read_csv(const std::filesystem::path& p);
// pid of role/id from the run directory's processes.csv (-1 if absent).
pid_t pid_of(const std::filesystem::path& run_dir, const std::string& role, unsigned id);
bool process_alive(pid_t pid);

}  // namespace qswarm::test
