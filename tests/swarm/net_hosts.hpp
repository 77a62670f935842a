#pragma once
// Hosts for multi-process tests: network namespaces, each with its own address, made by the test
// and removed when it ends (nothing reaches a real interface). Needs root, ip and iptables.
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace qswarm::test {

inline std::string find_tool(const std::string& name) {
  for (const char* dir : {"/usr/sbin/", "/sbin/", "/usr/bin/", "/bin/"}) {
    std::string p = std::string(dir) + name;
    if (access(p.c_str(), X_OK) == 0) return p;
  }
  return "";
}

// Why namespace hosts cannot be made here ("": they can).
inline std::string net_hosts_unavailable() {
  if (geteuid() != 0) return "needs root to create network namespaces and iptables rules";
  if (find_tool("ip").empty() || find_tool("iptables").empty() || find_tool("nsenter").empty())
    return "needs ip, iptables and nsenter";
  if (std::system("ip netns add qsw-probe >/dev/null 2>&1 && ip netns del qsw-probe") != 0)
    return "network namespaces are not available here";
  return "";
}

class NetHosts {
 public:
  enum class Layout {
    // One subnet (10.77.0.0/24) on a bridge in the "hub" namespace, with a multicast route: a LAN.
    kBridge,
    // Host i on its own subnet (10.78.i+1.0/24), routed through the "hub" namespace, which
    // forwards unicast only: hosts that reach each other but share no multicast, as on most
    // clusters and between a lab's subnets. No host has a default or multicast route.
    kRouted,
  };
  NetHosts(int n, Layout layout)
      : layout_(layout), prefix_("qsw" + std::to_string(getpid()) + "-") {
    nsenter_ = find_tool("nsenter");
    sh("ip netns add " + ns("hub"));
    sh("ip -n " + ns("hub") + " link set lo up");
    if (layout_ == Layout::kBridge) {
      sh("ip -n " + ns("hub") + " link add br0 type bridge");
      sh("ip -n " + ns("hub") + " link set br0 up");
    } else {
      sh("ip netns exec " + ns("hub") + " sysctl -qw net.ipv4.ip_forward=1");
    }
    for (int i = 0; i < n; ++i) add_host();
  }
  ~NetHosts() {
    for (const std::string& h : hosts_) std::system(("ip netns del " + h + " 2>/dev/null").c_str());
    std::system(("ip netns del " + ns("hub") + " 2>/dev/null").c_str());
  }
  NetHosts(const NetHosts&) = delete;
  NetHosts& operator=(const NetHosts&) = delete;

  // One more host; returns its index.
  int add_host() {
    const int i = static_cast<int>(hosts_.size());
    const std::string h = ns(std::to_string(i)), port = "p" + std::to_string(i);
    sh("ip netns add " + h);
    sh("ip -n " + h + " link add eth0 type veth peer name " + port + " netns " + ns("hub"));
    sh("ip -n " + h + " addr add " + address(i) + "/24 dev eth0");
    sh("ip -n " + h + " link set lo up");
    sh("ip -n " + h + " link set eth0 up");
    if (layout_ == Layout::kBridge) {
      sh("ip -n " + h + " route add 224.0.0.0/4 dev eth0");
      sh("ip -n " + ns("hub") + " link set " + port + " master br0");
    } else {
      sh("ip -n " + ns("hub") + " addr add " + gateway(i) + "/24 dev " + port);
      sh("ip -n " + h + " route add 10.78.0.0/16 via " + gateway(i));
    }
    sh("ip -n " + ns("hub") + " link set " + port + " up");
    hosts_.push_back(h);
    return i;
  }

  std::string ns(const std::string& s) const { return prefix_ + s; }
  std::string address(int i) const {
    return layout_ == Layout::kBridge ? "10.77.0." + std::to_string(10 + i)
                                      : "10.78." + std::to_string(i + 1) + ".2";
  }
  std::string gateway(int i) const { return "10.78." + std::to_string(i + 1) + ".1"; }
  // argv run on host i. nsenter execs it in place (`ip netns exec` forks and waits), so the
  // child's pid is the program's own and a signal to it reaches the program.
  std::vector<std::string> exec(int i, std::vector<std::string> argv) const {
    std::vector<std::string> out = {nsenter_, "--net=/run/netns/" + ns(std::to_string(i)), "--"};
    out.insert(out.end(), argv.begin(), argv.end());
    return out;
  }
  void sh(const std::string& cmd) const {
    if (std::system(cmd.c_str()) != 0) throw std::runtime_error("failed: " + cmd);
  }
  // A shell command run on host i (or on the hub: -1).
  void on(int i, const std::string& cmd) const {
    sh("ip netns exec " + ns(i < 0 ? "hub" : std::to_string(i)) + " " + cmd);
  }
  // kRouted: host i cut off from every other host (the hub forwards nothing to or from it), or
  // back.
  void cut_off(int i, bool cut) const {
    const std::string op = cut ? "-A" : "-D";
    on(-1, "iptables " + op + " FORWARD -i p" + std::to_string(i) + " -j DROP");
    on(-1, "iptables " + op + " FORWARD -o p" + std::to_string(i) + " -j DROP");
  }
  // Packets a host's INPUT rules have dropped.
  long dropped(int i) const {
    const std::string out = "/tmp/" + prefix_ + "ipt.txt";
    std::system(("ip netns exec " + ns(std::to_string(i)) + " iptables -L INPUT -v -n -x > " + out)
                    .c_str());
    std::ifstream in(out);
    std::string line;
    long total = 0;
    while (std::getline(in, line)) {
      if (line.find("DROP") == std::string::npos) continue;
      std::istringstream fields(line);
      long pkts = 0;
      fields >> pkts;
      total += pkts;
    }
    std::remove(out.c_str());
    return total;
  }

 private:
  Layout layout_;
  std::string prefix_, nsenter_;
  std::vector<std::string> hosts_;
};

}  // namespace qswarm::test
