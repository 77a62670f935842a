#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/record/scene.hpp"
#include "common/view/foxglove_protocol.hpp"
#include "common/view/view_feed.hpp"

namespace qswarm {

// Where the page's files and the npm packages are: $QSWARM_VIEW_PAGE_DIR and $QSWARM_NODE_MODULES
// when set (an installed or containerised supervisor), else the source tree the build came from.
std::string default_page_dir();
std::string default_node_modules();

// "" if a server could listen on address:port now, else why not (not an address, in use).
std::string probe_listen(const std::string& address, std::uint16_t port);

struct ViewServerOptions {
  std::string address = "127.0.0.1";          // loopback unless the user names another address
  std::uint16_t port = 8765;                  // 0: any free port (port() says which)
  std::string page_dir = default_page_dir();  // index.html, view.js, view.css
  std::string node_modules = default_node_modules();  // three, uplot (npm, tools/setup.sh)
  std::string name = "quadswarm";
  double frame_period_s = 0.05;  // 20 frames a second
  // HTTP and WebSocket together. At the limit a new connection takes the place of one that
  // matters less (an HTTP connection waiting for a request, a WebSocket subscribed to nothing or
  // reading nothing), so a few held sockets never keep a viewer out.
  std::size_t max_connections = 64;
  double subscribe_within_s = 120.0;  // a WebSocket subscribed to nothing after this is closed
  std::size_t max_queue_frames = 64;  // per client, before its frames are dropped
  std::size_t max_queue_bytes = 16u << 20;    // per client
  std::size_t max_message_bytes = 64u << 10;  // a client frame above this ends its session
  double client_messages_per_s = 20.0;        // sustained; bursts of 5 s worth pass
  std::size_t strikes = 50;  // floods or malformed frames before the session is closed
  // Where the server says what it refused, once per kind and session (the supervisor's log).
  std::function<void(const std::string&)> log;
};

// What the server served and refused, since it started.
// Every counter of the view, named once: the struct below, its JSON, and the server's atomics
// are all made from this list.
#define QSWARM_VIEW_COUNTERS(X)                                                 \
  X(connections)         /* TCP connections accepted */                         \
  X(refused_connections) /* over max_connections */                             \
  X(http_requests)                                                              \
  X(not_found)                                                                  \
  X(sessions)         /* WebSocket sessions opened */                           \
  X(open_sessions)    /* now */                                                 \
  X(refused_upgrades) /* no sub-protocol of ours, or a bad handshake */         \
  X(frames_sent)                                                                \
  X(frames_dropped) /* for a client whose queue was full */                     \
  X(malformed)      /* client frames that were not a JSON op we parse */        \
  X(oversized)      /* client frames above max_message_bytes */                 \
  X(flooded)        /* client frames beyond the rate */                         \
  X(refused_ops)    /* ops we do not serve, bad subscriptions, binary frames */ \
  X(closed_for_abuse)                                                           \
  X(refused_hosts) /* a Host header that names another site (DNS rebinding) */  \
  X(evicted)       /* closed to make room for a new connection at the limit */  \
  X(idle_closed)   /* WebSockets closed for subscribing to nothing */

struct ViewCounts {
#define QSWARM_VIEW_COUNT_FIELD(name) std::uint64_t name = 0;
  QSWARM_VIEW_COUNTERS(QSWARM_VIEW_COUNT_FIELD)
#undef QSWARM_VIEW_COUNT_FIELD
  std::string json() const;
};

// A replay's clock and controls (swarm view); a live run has none.
class ViewPlayback {
 public:
  virtual ~ViewPlayback() = default;
  // What became due by wall time `wall_s`. `reset`: the model must forget the run first (a seek).
  virtual ViewBatch advance(double wall_s, bool& reset) = 0;
  // play, pause, seek (t), speed: "" when done, else why not.
  virtual std::string control(const view::ClientOp& op, double wall_s) = 0;
  virtual std::string state_json() const = 0;
};

struct ViewServerError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The live view's server: one thread, one port, HTTP for the page and its libraries, WebSocket
// for Foxglove's protocol (the page is a Foxglove client too). Every frame period it takes what
// the feed (or a replay) has, turns it into the page's frame and the protobuf channels' messages,
// and queues them for each subscribed client; a client whose queue is full loses frames (counted)
// and gets a fresh snapshot once it reads again. Clients can only subscribe: nothing they send
// reaches the run.
class ViewServer {
 public:
  // `scene`: where the swarm should meet and its slots, for the 3D scene channel.
  ViewServer(ViewServerOptions opts, ViewFeed& feed, std::string run_info, SceneSettings scene,
             ViewPlayback* playback = nullptr);
  ~ViewServer();
  ViewServer(const ViewServer&) = delete;
  ViewServer& operator=(const ViewServer&) = delete;

  // Binds and starts the thread. Throws ViewServerError naming the address and why (in use, not
  // an address of this host).
  void start();
  void stop();
  // Waits (at most `timeout_s`) until what the feed holds now went out in a frame and every
  // client's queue is empty: the end of a run reaches the pages before the server stops.
  void flush(double timeout_s);
  std::uint16_t port() const;
  std::string url() const;
  ViewCounts counts() const;
  const std::vector<FoxgloveChannel>& channels() const;

  class Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace qswarm
