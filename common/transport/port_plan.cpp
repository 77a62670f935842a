#include "common/transport/port_plan.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <ifaddrs.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace qswarm {

std::optional<std::pair<int, int>> parse_unicast_peers(const std::string& text, std::string& why) {
  int first = -1, count = -1, used = 0;
  if (std::sscanf(text.c_str(), "%d:%d%n", &first, &count, &used) != 2 ||
      used != static_cast<int>(text.size()) || first < 0 || count < 1 ||
      first > PortPlan::kMaxParticipantId + 1 - count) {
    why = "\"" + text + "\": expected FIRST:COUNT, participant ids within 0.." +
          std::to_string(PortPlan::kMaxParticipantId);
    return std::nullopt;
  }
  return std::pair{first, count};
}

namespace {

// Whether a UDP port can be bound at `address` (any address when empty or "any"), alone or, with
// `shared`, beside sockets that allow it (SO_REUSEADDR).
bool port_free(std::uint32_t port, const std::string& address, std::string* why,
               bool shared = false) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    if (why) *why = std::string("socket: ") + std::strerror(errno);
    return false;
  }
  const int on = 1;
  if (shared) (void)::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_ANY);
  if (!address.empty() && address != "any") inet_pton(AF_INET, address.c_str(), &a.sin_addr);
  const bool ok = ::bind(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) == 0;
  if (!ok && why) *why = std::strerror(errno);
  ::close(fd);
  return ok;
}

}  // namespace

std::string participant_ports_problem(std::uint32_t domain, int id, const std::string& address) {
  if (domain > PortPlan::kMaxDomain)
    return "domain " + std::to_string(domain) + " is beyond " +
           std::to_string(PortPlan::kMaxDomain);
  if (id < 0 || id > PortPlan::kMaxParticipantId)
    return "participant id " + std::to_string(id) + " is outside 0..544";
  for (const std::uint32_t port :
       {PortPlan::discovery_port(domain, id), PortPlan::data_port(domain, id)}) {
    std::string why;
    if (!port_free(port, address, &why)) {
      return "UDP port " + std::to_string(port) + " of participant id " + std::to_string(id) +
             " on domain " + std::to_string(domain) + " cannot be bound (" + why +
             "): another run on this domain, or another program, holds it";
    }
  }
  return "";
}

std::string state_multicast_group(std::uint64_t run_id) {
  // splitmix64's finaliser: nearby run ids land on distant groups.
  std::uint64_t h = run_id + 0x9e3779b97f4a7c15ULL;
  h = (h ^ (h >> 30)) * 0xbf58476d1ce4e5b9ULL;
  h = (h ^ (h >> 27)) * 0x94d049bb133111ebULL;
  h ^= h >> 31;
  return "239.255." + std::to_string(1 + h % 254) + "." + std::to_string(1 + (h >> 8) % 254);
}

std::string multicast_port_problem(const std::string& group, std::uint32_t port,
                                   const std::string& address) {
  for (const std::string& at : {group, address}) {
    std::string why;
    if (port_free(port, at, &why, /*shared=*/true)) continue;
    std::string problem = "UDP port " + std::to_string(port);
    problem += " at " + at;
    problem += " cannot be shared (" + why;
    problem += "): another program holds it alone";
    return problem;
  }
  return "";
}

bool this_process_holds_udp_port(std::uint32_t port) {
  std::ifstream table("/proc/self/net/udp");
  std::string line;
  std::getline(table, line);  // the header
  std::vector<std::string> inodes;
  while (std::getline(table, line)) {
    std::istringstream row(line);
    std::string slot, local, remote, state, queues, timer, retransmits, uid, timeout, inode;
    if (!(row >> slot >> local >> remote >> state >> queues >> timer >> retransmits >> uid >>
          timeout >> inode))
      continue;
    const std::size_t colon = local.find(':');
    if (colon == std::string::npos) continue;
    if (std::stoul(local.substr(colon + 1), nullptr, 16) == port)
      inodes.push_back("socket:[" + inode + "]");
  }
  if (inodes.empty()) return false;
  std::error_code ec;
  for (const auto& fd : std::filesystem::directory_iterator("/proc/self/fd", ec)) {
    std::error_code link_ec;
    const std::string target = std::filesystem::read_symlink(fd.path(), link_ec).string();
    if (!link_ec && std::find(inodes.begin(), inodes.end(), target) != inodes.end()) return true;
  }
  return false;
}

std::optional<int> free_participant_block(std::uint32_t domain, int count,
                                          const std::string& address, int first) {
  for (int b = first; b + count - 1 <= PortPlan::kMaxParticipantId; ++b) {
    int taken = -1;
    for (int id = b; id < b + count; ++id) {
      if (!participant_ports_problem(domain, id, address).empty()) {
        taken = id;
        break;
      }
    }
    if (taken < 0) return b;
    b = taken;  // the next block starts after the taken id
  }
  return std::nullopt;
}

namespace {

struct Held {
  int first = 0, count = 0;
};

// The blocks live holders reserved on `domain`; files of dead holders are removed.
std::vector<Held> live_reservations(const std::filesystem::path& dir, std::uint32_t domain) {
  std::vector<Held> out;
  const std::string prefix = "domain-" + std::to_string(domain) + "-";
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    std::ifstream in(e.path());
    long pid = 0;
    Held h;
    if (!(in >> pid >> h.first >> h.count) || pid <= 0) continue;  // being written, or not ours
    if (::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH) {
      std::filesystem::remove(e.path(), ec);
      continue;
    }
    out.push_back(h);
  }
  return out;
}

}  // namespace

std::optional<PortReservation> PortReservation::reserve(std::uint32_t domain, int count,
                                                        const std::string& address,
                                                        const std::string& registry) {
  const std::filesystem::path dir(registry);
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  // Everyone on the host may reserve: a run as another user must not be locked out.
  std::filesystem::permissions(dir, std::filesystem::perms::all, ec);
  const std::string lock_path = (dir / "lock").string();
  const int lock = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
  if (lock < 0 || ::flock(lock, LOCK_EX) != 0) {
    const std::string why = std::strerror(errno);
    if (lock >= 0) ::close(lock);
    throw std::runtime_error("cannot lock the port registry " + lock_path + ": " + why);
  }
  const std::vector<Held> held = live_reservations(dir, domain);
  std::optional<int> base;
  for (int first = 0; first + count - 1 <= PortPlan::kMaxParticipantId;) {
    const std::optional<int> b = free_participant_block(domain, count, address, first);
    if (!b) break;
    int past = -1;  // the end of a reservation the candidate overlaps
    for (const Held& h : held)
      if (*b < h.first + h.count && h.first < *b + count) past = std::max(past, h.first + h.count);
    if (past < 0) {
      base = b;
      break;
    }
    first = past;
  }
  std::optional<PortReservation> out;
  if (base) {
    const std::filesystem::path file =
        dir / ("domain-" + std::to_string(domain) + "-" + std::to_string(::getpid()) + "-" +
               std::to_string(*base));
    std::ofstream f(file);
    f << ::getpid() << ' ' << *base << ' ' << count << '\n';
    f.flush();
    if (!f) {
      ::close(lock);
      throw std::runtime_error("cannot write the port registry " + file.string());
    }
    out.emplace(PortReservation(*base, file.string()));
  }
  ::close(lock);  // releases the lock
  return out;
}

PortReservation::~PortReservation() {
  if (file_.empty()) return;
  std::error_code ec;
  std::filesystem::remove(file_, ec);
}

std::set<std::string> local_ipv4_addresses() {
  std::set<std::string> here;
  ifaddrs* list = nullptr;
  if (getifaddrs(&list) != 0) return here;
  for (const ifaddrs* i = list; i != nullptr; i = i->ifa_next) {
    if (i->ifa_addr == nullptr || i->ifa_addr->sa_family != AF_INET) continue;
    const in_addr a = reinterpret_cast<const sockaddr_in*>(i->ifa_addr)->sin_addr;
    char text[INET_ADDRSTRLEN] = {};
    inet_ntop(AF_INET, &a, text, sizeof text);
    here.insert(text);
  }
  freeifaddrs(list);
  return here;
}

}  // namespace qswarm
