#include "tests/swarm/harness.hpp"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <google/protobuf/util/json_util.h>

#include <cerrno>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace qswarm::test {

std::string bin(const std::string& name) { return std::string(QSWARM_BIN_DIR) + "/" + name; }
std::string scenario(const std::string& name) {
  return std::string(QSWARM_SOURCE_DIR) + "/scenarios/" + name + ".txtpb";
}

std::filesystem::path fresh_dir(const std::string& name) {
  std::filesystem::path p = std::filesystem::path(QSWARM_TEST_RUNS_DIR) / name;
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p.parent_path());
  return p;
}

std::filesystem::path fresh_dir_path(const std::string& name) {
  return std::filesystem::path(QSWARM_TEST_RUNS_DIR) / name;
}

Child::Child(const std::vector<std::string>& argv, const std::filesystem::path& log) : log_(log) {
  std::filesystem::create_directories(log.parent_path());
  pid_ = fork();
  if (pid_ < 0) throw std::runtime_error("fork failed");
  if (pid_ == 0) {
    const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      dup2(fd, STDOUT_FILENO);
      dup2(fd, STDERR_FILENO);
    }
    std::vector<char*> args;
    args.reserve(argv.size() + 1);
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
}

Child::~Child() {
  if (!done_ && pid_ > 0) {
    ::kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
  }
}

bool Child::running() {
  if (done_) return false;
  int status = 0;
  if (waitpid(pid_, &status, WNOHANG) == pid_) {
    done_ = true;
    code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return false;
  }
  return true;
}

Result Child::wait(double timeout_s) {
  if (!wait_for([&] { return !running(); }, timeout_s)) {
    ::kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
    done_ = true;
    return {-1,
            read_file(log_) + "\n[harness: timed out after " + std::to_string(timeout_s) + " s]"};
  }
  return {code_, read_file(log_)};
}

Result run(const std::vector<std::string>& argv, double timeout_s) {
  static int counter = 0;
  const std::filesystem::path log =
      std::filesystem::path(QSWARM_TEST_RUNS_DIR) / "logs" /
      (std::to_string(getpid()) + "-" + std::to_string(counter++) + ".log");
  Child c(argv, log);
  return c.wait(timeout_s);
}

bool wait_for(const std::function<bool()>& cond, double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < deadline) {
    if (cond()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return cond();
}

std::string read_file(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

double stats_value(const std::filesystem::path& run_dir, unsigned id, const std::string& key) {
  std::ifstream in(run_dir / ("agent-" + std::to_string(id) + ".stats"));
  std::string k;
  double v = 0.0;
  while (in >> k >> v)
    if (k == key) return v;
  return -1.0;
}

records::Summary read_summary(const std::filesystem::path& run_dir) {
  records::Summary s;
  google::protobuf::util::JsonParseOptions opt;
  opt.ignore_unknown_fields = true;
  const auto st =
      google::protobuf::util::JsonStringToMessage(read_file(run_dir / "summary.json"), &s, opt);
  if (!st.ok()) throw std::runtime_error("summary.json: " + st.ToString());
  return s;
}

std::vector<std::map<std::string, std::string>> read_csv(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::string line;
  std::vector<std::string> header;
  std::vector<std::map<std::string, std::string>> rows;
  const auto split = [](const std::string& l) {
    std::vector<std::string> out;
    std::string cur;
    bool quoted = false;
    for (char c : l) {
      if (c == '"') {
        quoted = !quoted;
      } else if (c == ',' && !quoted) {
        out.push_back(cur);
        cur.clear();
      } else {
        cur += c;
      }
    }
    out.push_back(cur);
    return out;
  };
  if (!std::getline(in, line)) return rows;
  header = split(line);
  while (std::getline(in, line)) {
    const auto cells = split(line);
    if (cells.size() != header.size()) continue;  // a row being written
    std::map<std::string, std::string> row;
    for (size_t i = 0; i < header.size(); ++i) row[header[i]] = cells[i];
    rows.push_back(std::move(row));
  }
  return rows;
}

pid_t pid_of(const std::filesystem::path& run_dir, const std::string& role, unsigned id) {
  for (const auto& row : read_csv(run_dir / "processes.csv")) {
    if (row.at("role") == role && std::stoul(row.at("id")) == id) return std::stoi(row.at("pid"));
  }
  return -1;
}

bool process_alive(pid_t pid) {
  if (pid <= 0) return false;
  if (::kill(pid, 0) != 0) return errno != ESRCH;
  // A zombie is not alive: look at /proc.
  const std::string stat = read_file("/proc/" + std::to_string(pid) + "/stat");
  const auto close = stat.rfind(')');
  return close != std::string::npos && close + 2 < stat.size() && stat[close + 2] != 'Z';
}

}  // namespace qswarm::test
