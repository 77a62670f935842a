#include "common/record/run_dir.hpp"

#include <fcntl.h>
#include <google/protobuf/util/json_util.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <fstream>
#include <sstream>

#include "proto/records.pb.h"

namespace fs = std::filesystem;

#include "common/scenario/proto_util.hpp"

namespace qswarm {

std::string safe_name(const std::string& name) {
  std::string out;
  for (const char c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '.' || c == '-' || c == '_';
    out += ok ? c : '_';
    if (out.size() == 64) break;
  }
  while (!out.empty() && out.front() == '.') out.front() = '_';
  return out.empty() ? "unnamed" : out;
}

namespace {

// Creates dir (if needed) and the marker; false if the marker exists (another run has it).
bool try_claim(const fs::path& dir, const std::string& flag) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw RunDirError(flag + " " + dir.string() + ": cannot create (" + ec.message() + ")");
  if (!fs::is_directory(dir)) throw RunDirError(flag + " " + dir.string() + ": not a directory");
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().filename() == ".swarm-run") return false;
    throw RunDirError(flag + " " + dir.string() +
                      ": expected a new or empty directory; it holds files (e.g. " +
                      entry.path().filename().string() + "): choose another --out");
  }
  const std::string marker = (dir / ".swarm-run").string();
  const int fd = ::open(marker.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) {
    if (errno == EEXIST) return false;
    throw RunDirError(flag + " " + dir.string() + ": cannot write (" + std::strerror(errno) + ")");
  }
  const std::string pid = std::to_string(::getpid()) + "\n";
  const bool ok = ::write(fd, pid.data(), pid.size()) == static_cast<ssize_t>(pid.size());
  ::close(fd);
  if (!ok) throw RunDirError(flag + " " + dir.string() + ": cannot write (disk full?)");
  return true;
}

}  // namespace

std::string run_timestamp() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y%m%d-%H%M%S", std::localtime(&t));
  return buf;
}

fs::path claim_run_dir(const std::string& out, const std::string& scenario_name,
                       const std::string& timestamp, const fs::path& root) {
  if (!out.empty()) {
    if (!try_claim(out, "--out")) {
      throw RunDirError("--out " + out + ": another run is writing there; choose another --out");
    }
    return fs::absolute(out);
  }
  const fs::path base = root / (timestamp + "-" + safe_name(scenario_name));
  for (int k = 1; k < 1000; ++k) {
    const fs::path dir = k == 1 ? base : fs::path(base.string() + "-" + std::to_string(k));
    if (fs::exists(dir)) continue;
    if (try_claim(dir, "run directory")) return fs::absolute(dir);
  }
  throw RunDirError("run directory " + base.string() + ": no free name; use --out");
}

bool write_fallback_summary(const fs::path& dir, const RunConfig& rc, const std::string& reason,
                            double wall_time_s) {
  records::Summary s;
  s.set_scenario(rc.name);
  s.set_converged(false);
  s.set_convergence_time_s(-1.0);
  s.set_end_reason(reason);
  s.set_wall_time_s(wall_time_s);
  s.set_run_id(rc.transport.run_id);
  s.set_seed(static_cast<std::uint32_t>(rc.seed));
  s.set_agents_expected(static_cast<std::uint32_t>(rc.agents.size()));
  s.set_law(to_string(rc.agent.law.kind));
  s.set_mode(rc.agent.mode == AgentMode::kQuadcopter ? "quadcopter" : "particle");
  for (int k = 0; k < 3; ++k) s.add_initial_average(rc.initial_average()[k]);
  const std::string json = to_json(s);
  std::ofstream f(dir / "summary.json");
  f << json;
  f.flush();
  return static_cast<bool>(f);
}

bool amend_summary(const fs::path& dir, const std::vector<std::string>& problems) {
  std::ifstream in(dir / "summary.json");
  std::stringstream text;
  text << in.rdbuf();
  records::Summary s;
  if (!google::protobuf::util::JsonStringToMessage(text.str(), &s).ok()) return false;
  s.set_converged(false);
  std::string reason = s.end_reason();
  for (const std::string& p : problems) reason += "; " + p;
  s.set_end_reason(reason);
  std::ofstream out(dir / "summary.json");
  out << to_json(s);
  out.flush();
  return static_cast<bool>(out);
}

}  // namespace qswarm
