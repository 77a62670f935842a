#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace qswarm {

// A Fast DDS Discovery Server (server id 0, the prefix clients assume, or its index in a list of
// servers): the compose swarm's agents and supervisor, and those of hosts without multicast,
// discover each other through it instead of by multicast, which container networks and routed
// hosts do not carry. Servers of one list know each other, so each holds every participant and
// clients listing them all keep discovering while one is down. Data still flows directly between
// the participants. This is what `fastdds discovery -i 0 -l ADDR -p PORT` runs, without needing
// Python in the image.
class DiscoveryServer {
 public:
  // `listen`: an IPv4 address or a host name (resolved); `port`: its metatraffic UDP port.
  // `participant_id`: its place in the port plan (a run's own server: `port` is that id's
  // discovery port, and the server's data port is the id's too); -1: Fast DDS picks (compose,
  // where the server is alone in its container).
  // `index`: its place in the servers' list (its GUID prefix); `servers`: that list, resolved
  // (resolve_discovery_servers; empty: it is alone), whose other entries it connects to.
  DiscoveryServer(std::uint32_t domain_id, const std::string& listen, std::uint16_t port,
                  int participant_id = -1, int index = 0,
                  const std::vector<std::pair<std::string, std::uint16_t>>& servers = {});
  ~DiscoveryServer();
  DiscoveryServer(const DiscoveryServer&) = delete;
  DiscoveryServer& operator=(const DiscoveryServer&) = delete;

  const std::string& address() const { return address_; }
  // Participants (clients) the server currently knows.
  int clients() const;

  // The server's own announcements as its participant applied them: none at start, and a period
  // no run reaches (discovery_server.cpp says why).
  static constexpr std::int32_t kNeverSeconds = 100 * 24 * 3600;
  struct Announcements {
    std::uint32_t initial = 0;
    double period_s = 0;
  };
  Announcements announcements() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
  std::string address_;
};

}  // namespace qswarm
