#include "common/view/view_server.hpp"

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <list>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <thread>
#include <variant>

#include "common/record/json_writer.hpp"
#include "common/view/view_channels.hpp"
#include "common/view/view_model.hpp"

namespace qswarm {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;

std::string default_page_dir() {
  const char* env = std::getenv("QSWARM_VIEW_PAGE_DIR");
  return env && *env ? env : QSWARM_VIEW_PAGE_DIR;
}

std::string default_node_modules() {
  const char* env = std::getenv("QSWARM_NODE_MODULES");
  return env && *env ? env : QSWARM_NODE_MODULES;
}

namespace {
// The address a view may listen on ("" and `addr` set), or why not: an IP address that is not a
// multicast group. An IPv4 address written as IPv6 (::ffff:127.0.0.1) is that IPv4 address, so
// that a loopback one keeps the Host check.
std::string listen_address(const std::string& address, asio::ip::address& addr) {
  beast::error_code ec;
  addr = asio::ip::make_address(address, ec);
  if (ec) return "'" + address + "' is not an IP address";
  if (addr.is_v6() && addr.to_v6().is_v4_mapped())
    addr = asio::ip::make_address_v4(asio::ip::v4_mapped, addr.to_v6());
  if (addr.is_multicast())
    return "'" + address + "' is a multicast group, not an address to listen on";
  return "";
}
}  // namespace

std::string probe_listen(const std::string& address, std::uint16_t port) {
  asio::io_context ioc;
  beast::error_code ec;
  asio::ip::address addr;
  if (std::string why = listen_address(address, addr); !why.empty()) return why;
  tcp::acceptor a(ioc);
  const tcp::endpoint ep(addr, port);
  a.open(ep.protocol(), ec);
  if (!ec) a.set_option(asio::socket_base::reuse_address(true), ec);
  if (!ec) a.bind(ep, ec);
  if (!ec) a.listen(1, ec);
  return ec ? "cannot listen on " + address + ":" + std::to_string(port) + ": " + ec.message() : "";
}

std::string ViewCounts::json() const {
  std::string out;
  JsonWriter w(out);
#define QSWARM_VIEW_COUNT_PAIR(name) {#name, name},
  const std::pair<const char*, std::uint64_t> fields[] = {
      QSWARM_VIEW_COUNTERS(QSWARM_VIEW_COUNT_PAIR)};
#undef QSWARM_VIEW_COUNT_PAIR
  w.raw("{");
  bool first = true;
  for (const auto& [k, v] : fields) {
    if (!first) w.raw(",");
    first = false;
    w.key(k).integer(static_cast<std::int64_t>(v));
  }
  w.raw("}");
  return out;
}

namespace {

double steady_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::int64_t realtime_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::uint64_t sim_ns(double t_s) {
  return t_s > 0.0 && std::isfinite(t_s) ? static_cast<std::uint64_t>(std::llround(t_s * 1e9)) : 0;
}

// One message queued for a client: a per-client header (the binary frame's opcode and
// subscription id) before a payload that every client shares.
struct Outgoing {
  std::string head;
  std::shared_ptr<const std::string> body;
  bool binary = false;
  std::size_t size() const { return head.size() + (body ? body->size() : 0); }
};

std::shared_ptr<const std::string> share(std::string s) {
  return std::make_shared<const std::string>(std::move(s));
}

struct Counters {
// NOLINTNEXTLINE(bugprone-macro-parentheses): the argument is a member's name, not an expression
#define QSWARM_VIEW_COUNT_ATOMIC(name) std::atomic<std::uint64_t> name{0};
  QSWARM_VIEW_COUNTERS(QSWARM_VIEW_COUNT_ATOMIC)
#undef QSWARM_VIEW_COUNT_ATOMIC
};

}  // namespace

class WsSession;
class HttpSession;

class ViewServer::Impl {
 public:
  Impl(ViewServerOptions opts, ViewFeed& feed, std::string run_info, SceneSettings scene,
       ViewPlayback* playback)
      : opts_(std::move(opts)),
        feed_(feed),
        model_(std::move(run_info)),
        scene_settings_(scene),
        scene_(std::move(scene)),
        playback_(playback),
        channels_(view_channels()),
        session_id_(std::to_string(realtime_ns())) {}
  ~Impl() {
    stop();
    // Sockets and timers go before the loop they belong to (ioc_ is the last member, so it is
    // destroyed first of the rest: handlers it still holds see the counters alive).
    sessions_.clear();
    http_.clear();
    timer_.reset();
    acceptor_.reset();
  }
  ViewCounts counts() const;

  void start();
  void stop();
  void log(const std::string& s) {
    if (opts_.log) opts_.log(s);
  }
  // Says `what` once per kind for the server's life (the counters keep the totals).
  void log_once(const std::string& kind, const std::string& what) {
    if (logged_.insert(kind).second) log(what);
  }

  ViewServerOptions opts_;
  ViewFeed& feed_;
  ViewModel model_;
  SceneSettings scene_settings_;
  SceneBuilder scene_;  // the newest sample of every agent present, for the scene channel
  ViewPlayback* playback_;
  std::vector<FoxgloveChannel> channels_;
  std::optional<tcp::acceptor> acceptor_;
  std::optional<asio::steady_timer> timer_;
  std::thread thread_;
  std::mutex done_mu_;
  std::condition_variable done_cv_;
  bool done_ = false;
  std::string session_id_;
  Counters counts_;
  bool loopback_ = true;  // listening on a loopback address (set by start())
  std::atomic<std::size_t> open_connections_{0};
  std::list<std::shared_ptr<WsSession>> sessions_;
  std::list<std::weak_ptr<HttpSession>> http_;  // to close idle keep-alive connections at stop
  std::set<std::string> logged_;
  std::uint16_t port_ = 0;
  bool started_ = false;
  double next_heartbeat_s_ = 0.0;
  bool force_frame_ = false;
  bool stopping_ = false;
  std::atomic<std::uint64_t> ticks_{0};
  std::atomic<std::size_t> queued_{0};  // messages in every client's queue  // a playback control
                                        // changed the state: say so in the next frame

  std::string snapshot() const {
    return model_.snapshot_json(playback_ ? playback_->state_json() : "null");
  }
  void accept();
  // Closes the connection that matters least to make room for a new one at the limit: one waiting
  // for an HTTP request (oldest first), else a WebSocket subscribed to nothing, else one whose
  // queue is full. A session that subscribed and reads is never closed for another. False: none.
  bool make_room();
  void tick();
  // Whether a request's Host header names this server: an IP address (any: a user who listens
  // elsewhere reaches it by address) or localhost, with or without a port. A server listening on
  // loopback answers nothing else; one listening elsewhere also answers names (a user's hostname).
  bool host_allowed(const std::string& host) const {
    std::string h = host;
    if (!h.empty() && h.front() == '[') {  // [v6]:port
      const std::size_t close = h.find(']');
      if (close == std::string::npos) return false;
      h = h.substr(1, close - 1);
    } else if (const std::size_t colon = h.find(':');
               colon != std::string::npos && h.find(':', colon + 1) == std::string::npos) {
      h = h.substr(0, colon);
    }
    if (h == "localhost") return true;
    beast::error_code ec;
    asio::ip::make_address(h, ec);
    if (!ec) return true;
    return !loopback_;
  }
  void remove(WsSession* s);
  using HttpReply = std::variant<http::response<http::string_body>, http::response<http::file_body>,
                                 http::response<http::empty_body>>;
  HttpReply serve_http(const std::string& target, const http::request<http::empty_body>& req);

  asio::io_context ioc_{1};  // last: see ~Impl
};

class WsSession : public std::enable_shared_from_this<WsSession> {
 public:
  WsSession(ViewServer::Impl& server, tcp::socket socket, std::string subprotocol)
      : server_(server),
        ws_(std::move(socket)),
        subprotocol_(std::move(subprotocol)),
        proto_(server.channels_),
        tokens_(server.opts_.client_messages_per_s * 5.0),
        last_s_(steady_s()) {}

  void run(const http::request<http::empty_body>& req) {
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    const std::string proto = subprotocol_;
    ws_.set_option(websocket::stream_base::decorator([proto](websocket::response_type& res) {
      res.set(http::field::sec_websocket_protocol, proto);
      res.set(http::field::server, "quadswarm view");
    }));
    ws_.read_message_max(server_.opts_.max_message_bytes);
    ws_.async_accept(req, [self = shared_from_this()](beast::error_code ec) {
      if (ec) {
        ++self->server_.counts_.refused_upgrades;
        self->close_session();
        return;
      }
      ++self->server_.counts_.sessions;
      ++self->server_.counts_.open_sessions;
      self->open_ = true;
      self->quiet_since_s_ = steady_s();
      self->send_text(server_info_json(self->server_.opts_.name, self->server_.session_id_));
      self->send_text(advertise_json(self->server_.channels_));
      self->read();
    });
  }

  // Queues a message; false (and counted) when the client's queue is full.
  bool push(Outgoing m) {
    if (!open_ || closing_) return false;
    if (queue_.size() >= server_.opts_.max_queue_frames ||
        queued_bytes_ + m.size() > server_.opts_.max_queue_bytes) {
      ++server_.counts_.frames_dropped;
      ++dropped_;
      stale_ = true;  // it missed a frame: it gets a snapshot when it has room again
      if (dropped_ == 1)
        server_.log_once("drop", "view: a client is not keeping up; its frames are dropped");
      return false;
    }
    queued_bytes_ += m.size();
    queue_.push_back(std::move(m));
    ++server_.queued_;
    if (!writing_) write();
    return true;
  }
  void send_text(std::string s) { push(Outgoing{std::move(s), nullptr, false}); }
  void send_channel(std::uint32_t channel, std::uint64_t log_ns,
                    const std::shared_ptr<const std::string>& payload) {
    const std::optional<std::uint32_t> sub = proto_.subscription(channel);
    if (!sub) return;
    std::string head = message_frame(*sub, log_ns, {});
    push(Outgoing{std::move(head), payload, true});
  }
  bool subscribed(std::uint32_t channel) const { return proto_.subscription(channel).has_value(); }
  // Whether a full snapshot must replace the next frame (it missed one), and whether it has room.
  bool stale() const { return stale_; }
  bool has_room() const { return queue_.size() < server_.opts_.max_queue_frames / 2; }
  void fresh() { stale_ = false; }
  // Subscribed to nothing (a session that has not finished its handshake yet, or that only holds
  // a connection): seconds since it opened, or -1 for one that subscribed.
  double unsubscribed_for_s(double now) const {
    if (closed_) return -1.0;
    if (!open_) return 0.0;
    return proto_.subscriptions() == 0 ? now - quiet_since_s_ : -1.0;
  }
  // Subscribed, but not reading what it is sent: its queue is full.
  bool stuck() const { return open_ && !closed_ && stale_ && !has_room(); }

  void close_session() {
    if (closed_) return;
    closed_ = true;
    if (open_) --server_.counts_.open_sessions;
    open_ = false;
    beast::error_code ec;
    beast::get_lowest_layer(ws_).socket().close(ec);
    server_.queued_ -= queue_.size();
    queue_.clear();
    --server_.open_connections_;
    server_.remove(this);
  }

  void shutdown() {
    beast::error_code ec;
    beast::get_lowest_layer(ws_).socket().close(ec);
  }

 private:
  void read() {
    ws_.async_read(
        in_, [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_read(ec); });
  }

  void on_read(beast::error_code ec) {
    if (ec) {
      if (ec == websocket::error::message_too_big) {
        ++server_.counts_.oversized;
        server_.log_once("oversized", "view: a client sent a frame above " +
                                          std::to_string(server_.opts_.max_message_bytes) +
                                          " bytes; its session was closed");
      } else if (ec.category() == websocket::make_error_code(websocket::error::closed).category() &&
                 ec != websocket::error::closed) {
        // A frame that breaks the WebSocket protocol (bad opcode, unmasked, text that is not
        // UTF-8, ...): Beast closes the session; we count it.
        ++server_.counts_.malformed;
        server_.log_once("protocol", "view: a client broke the WebSocket protocol (" +
                                         ec.message() + "); its session was closed");
      }
      close_session();
      return;
    }
    const bool binary = ws_.got_binary();
    const std::string text = beast::buffers_to_string(in_.data());
    in_.consume(in_.size());
    // A token bucket: client_messages_per_s sustained, five seconds of it at once.
    const double now = steady_s();
    const double cap = server_.opts_.client_messages_per_s * 5.0;
    tokens_ = std::min(cap, tokens_ + (now - last_s_) * server_.opts_.client_messages_per_s);
    last_s_ = now;
    if (tokens_ < 1.0) {
      ++server_.counts_.flooded;
      server_.log_once("flood", "view: a client sends faster than " +
                                    std::to_string(server_.opts_.client_messages_per_s) +
                                    " frames/s; the excess is refused");
      if (strike()) return;
      read();
      return;
    }
    tokens_ -= 1.0;
    if (binary) {
      ++server_.counts_.refused_ops;
      server_.log_once("binary",
                       "view: a client sent a binary frame (publishing, service "
                       "calls): refused, the view is read-only");
      send_text(status_json(2, "binary client frames are refused: this server only publishes"));
      if (strike()) return;
      read();
      return;
    }
    const bool subscribed_before = proto_.subscriptions() > 0;
    FoxgloveSession::Outcome o = proto_.handle_text(text);
    // Quiet from the moment it stops listening to anything, not from when it connected.
    if (subscribed_before && proto_.subscriptions() == 0) quiet_since_s_ = steady_s();
    if (o.malformed) {
      ++server_.counts_.malformed;
      server_.log_once("malformed", "view: a client sent a frame that is not a JSON op; refused");
      send_text(status_json(2, "malformed frame: expected a JSON object with an op"));
      if (strike()) return;
    }
    if (!o.refusals.empty()) {
      server_.counts_.refused_ops += o.refusals.size();
      std::string msg = o.refusals.front();
      if (o.refusals.size() > 1) msg += " (and " + std::to_string(o.refusals.size() - 1) + " more)";
      send_text(status_json(1, msg));
    }
    for (const std::uint32_t channel : o.subscribed) {
      // The page's channel starts with everything so far; then it gets the changes.
      if (channel == kViewChannel)
        send_channel(kViewChannel, sim_ns(server_.model_.time_s()), share(server_.snapshot()));
    }
    if (o.playback) {
      if (!server_.playback_) {
        ++server_.counts_.refused_ops;
        send_text(status_json(1, "playback control: this is a live run; the view is read-only"));
      } else if (const std::string err = server_.playback_->control(*o.playback, steady_s());
                 !err.empty()) {
        ++server_.counts_.refused_ops;
        send_text(status_json(1, "playback control: " + err));
      } else {
        server_.force_frame_ = true;
      }
    }
    read();
  }

  // True when the session was closed for too many refused frames.
  bool strike() {
    if (++strikes_ < server_.opts_.strikes) return false;
    ++server_.counts_.closed_for_abuse;
    server_.log_once("abuse", "view: closed a client's session after " +
                                  std::to_string(server_.opts_.strikes) + " refused frames");
    closing_ = true;
    ws_.async_close(websocket::close_reason(websocket::close_code::policy_error, "refused"),
                    [self = shared_from_this()](beast::error_code) { self->close_session(); });
    return true;
  }

  void write() {
    if (queue_.empty() || closed_) {
      writing_ = false;
      return;
    }
    writing_ = true;
    const Outgoing& m = queue_.front();
    ws_.binary(m.binary);
    std::array<asio::const_buffer, 2> bufs{asio::buffer(m.head),
                                           m.body ? asio::buffer(*m.body) : asio::const_buffer()};
    ws_.async_write(bufs, [self = shared_from_this()](beast::error_code ec, std::size_t) {
      if (ec) {
        self->writing_ = false;
        self->close_session();
        return;
      }
      ++self->server_.counts_.frames_sent;
      self->queued_bytes_ -= self->queue_.front().size();
      self->queue_.pop_front();
      --self->server_.queued_;
      self->write();
    });
  }

  ViewServer::Impl& server_;
  websocket::stream<beast::tcp_stream> ws_;
  std::string subprotocol_;
  FoxgloveSession proto_;
  beast::flat_buffer in_;
  std::deque<Outgoing> queue_;
  std::size_t queued_bytes_ = 0;
  bool writing_ = false, open_ = false, closed_ = false, closing_ = false, stale_ = false;
  double quiet_since_s_ = 0.0;  // when it opened, or last dropped its last subscription
  std::uint64_t dropped_ = 0;
  std::size_t strikes_ = 0;
  double tokens_, last_s_;

 public:
  friend class ViewServer::Impl;
};

class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(ViewServer::Impl& server, tcp::socket socket)
      : server_(server), stream_(std::move(socket)) {}
  ~HttpSession() {
    if (!upgraded_) --server_.open_connections_;
  }
  void shutdown() {
    beast::error_code ec;
    stream_.socket().close(ec);
  }
  // Waiting for a request (half-open, or kept alive between requests): the first to go when a new
  // connection needs room.
  bool idle() const { return awaiting_ && !upgraded_; }
  void read() {
    awaiting_ = true;
    parser_.emplace();
    parser_->header_limit(8 * 1024);
    parser_->body_limit(0);  // GET only: a body is refused
    stream_.expires_after(std::chrono::seconds(30));
    http::async_read(
        stream_, buffer_, *parser_,
        [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_read(ec); });
  }

 private:
  void on_read(beast::error_code ec) {
    awaiting_ = false;
    if (ec) {
      beast::error_code ignored;
      stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
      return;
    }
    ++server_.counts_.http_requests;
    http::request<http::empty_body> req = parser_->release();
    if (!server_.host_allowed(std::string(req[http::field::host]))) {
      // DNS rebinding: a page of some site whose name now points at 127.0.0.1 would read the view
      // through the user's browser; its requests name that site, not this host.
      ++server_.counts_.refused_hosts;
      server_.log_once("host", "view: refused a request for host '" +
                                   std::string(req[http::field::host]).substr(0, 80) +
                                   "' (not this host's address or localhost)");
      http::response<http::string_body> res{http::status::forbidden, req.version()};
      res.set(http::field::content_type, "text/plain");
      res.body() = "this view answers to its address or localhost only\n";
      res.prepare_payload();
      res.keep_alive(false);
      respond(ViewServer::Impl::HttpReply(std::move(res)));
      return;
    }
    if (websocket::is_upgrade(req)) {
      const std::string proto =
          choose_subprotocol(std::string(req[http::field::sec_websocket_protocol]));
      if (proto.empty()) {
        ++server_.counts_.refused_upgrades;
        server_.log_once("subprotocol",
                         "view: refused a WebSocket without the sub-protocol "
                         "foxglove.websocket.v1 or foxglove.sdk.v1");
        http::response<http::string_body> res{http::status::bad_request, req.version()};
        res.set(http::field::content_type, "text/plain");
        res.body() = "offer the sub-protocol foxglove.websocket.v1 or foxglove.sdk.v1\n";
        res.prepare_payload();
        res.keep_alive(false);
        respond(ViewServer::Impl::HttpReply(std::move(res)));
        return;
      }
      stream_.expires_never();
      upgraded_ = true;
      // What the kernel holds for a client that does not read is bounded too (beside its queue).
      beast::error_code ignored;
      stream_.socket().set_option(asio::socket_base::send_buffer_size(64 * 1024), ignored);
      auto ws = std::make_shared<WsSession>(server_, stream_.release_socket(), proto);
      server_.sessions_.push_back(ws);
      ws->run(req);
      return;
    }
    respond(server_.serve_http(std::string(req.target()), req));
  }

  void respond(ViewServer::Impl::HttpReply reply) {
    std::visit(
        [this](auto& res) {
          using Res = std::decay_t<decltype(res)>;
          auto sp = std::make_shared<Res>(std::move(res));
          const bool keep = sp->keep_alive();
          http::async_write(
              stream_, *sp,
              [self = shared_from_this(), sp, keep](beast::error_code ec, std::size_t) {
                if (ec || !keep) {
                  beast::error_code ignored;
                  self->stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
                  return;
                }
                self->read();
              });
        },
        reply);
  }

  ViewServer::Impl& server_;
  beast::tcp_stream stream_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::empty_body>> parser_;
  bool upgraded_ = false;
  bool awaiting_ = false;
};

void ViewServer::Impl::start() {
  beast::error_code ec;
  asio::ip::address addr;
  if (const std::string why = listen_address(opts_.address, addr); !why.empty())
    throw ViewServerError(why);
  const tcp::endpoint ep(addr, opts_.port);
  acceptor_.emplace(ioc_);
  timer_.emplace(ioc_);
  acceptor_->open(ep.protocol(), ec);
  if (!ec) acceptor_->set_option(asio::socket_base::reuse_address(true), ec);
  if (!ec) acceptor_->bind(ep, ec);
  if (!ec) acceptor_->listen(asio::socket_base::max_listen_connections, ec);
  if (ec) {
    throw ViewServerError("cannot listen on " + opts_.address + ":" + std::to_string(opts_.port) +
                          ": " + ec.message());
  }
  port_ = acceptor_->local_endpoint().port();
  loopback_ = addr.is_loopback();
  accept();
  timer_->expires_after(std::chrono::milliseconds(0));
  timer_->async_wait([this](beast::error_code e) {
    if (!e) tick();
  });
  started_ = true;
  thread_ = std::thread([this] {
    // A handler that throws (out of memory) loses its connection, never the supervisor: the loop
    // goes on with the others.
    while (true) {
      try {
        ioc_.run();
        break;
      } catch (const std::exception& e) {
        log(std::string("view: a handler failed: ") + e.what());
      }
    }
    std::lock_guard<std::mutex> lock(done_mu_);
    done_ = true;
    done_cv_.notify_all();
  });
}

void ViewServer::Impl::stop() {
  if (!started_) return;
  started_ = false;
  asio::post(ioc_, [this] {
    stopping_ = true;  // a tick already due must not arm the timer again
    beast::error_code ec;
    acceptor_->close(ec);
    timer_->cancel();
    for (auto& s : sessions_) s->shutdown();
    for (auto& w : http_)
      if (auto h = w.lock()) h->shutdown();
  });
  // Closed sockets end their handlers at once and the loop runs out of work; a handler that does
  // not (none is known) is cut off after three seconds.
  {
    std::unique_lock<std::mutex> lock(done_mu_);
    done_cv_.wait_for(lock, std::chrono::seconds(3), [this] { return done_; });
  }
  ioc_.stop();
  thread_.join();
}

void ViewServer::Impl::accept() {
  acceptor_->async_accept([this](beast::error_code ec, tcp::socket socket) {
    if (ec == asio::error::operation_aborted || !acceptor_->is_open()) return;
    if (!ec) {
      ++counts_.connections;
      if (open_connections_ >= opts_.max_connections && !make_room()) {
        ++counts_.refused_connections;
        log_once("connections", "view: refused a connection over the limit of " +
                                    std::to_string(opts_.max_connections) +
                                    " (every one subscribed and reading)");
        beast::error_code ignored;
        socket.close(ignored);
      } else {
        ++open_connections_;
        auto h = std::make_shared<HttpSession>(*this, std::move(socket));
        http_.remove_if([](const std::weak_ptr<HttpSession>& w) { return w.expired(); });
        http_.push_back(h);
        h->read();
      }
    }
    accept();
  });
}

bool ViewServer::Impl::make_room() {
  for (const std::weak_ptr<HttpSession>& w : http_) {
    const std::shared_ptr<HttpSession> h = w.lock();
    if (!h || !h->idle()) continue;
    h->shutdown();
    ++counts_.evicted;
    log_once("evicted", "view: at the limit of " + std::to_string(opts_.max_connections) +
                            " connections, closed one that sent no request to make room");
    return true;
  }
  const double now = steady_s();
  std::shared_ptr<WsSession> quiet, stuck;
  double longest = -1.0;
  for (const auto& s : sessions_) {
    const double quiet_s = s->unsubscribed_for_s(now);
    if (quiet_s > longest) {
      longest = quiet_s;
      quiet = s;
    }
    if (!stuck && s->stuck()) stuck = s;
  }
  const std::shared_ptr<WsSession> gone = quiet ? quiet : stuck;
  if (!gone) return false;
  gone->close_session();
  ++counts_.evicted;
  log_once("evicted-ws", "view: at the limit of " + std::to_string(opts_.max_connections) +
                             " connections, closed a WebSocket that " +
                             (quiet ? "subscribed to nothing" : "read nothing") + " to make room");
  return true;
}

void ViewServer::Impl::remove(WsSession* s) {
  // Deferred: the session may be inside its own handler.
  asio::post(ioc_, [this, s] {
    sessions_.remove_if([s](const std::shared_ptr<WsSession>& p) { return p.get() == s; });
  });
}

void ViewServer::Impl::tick() {
  const double now = steady_s();
  // A WebSocket that never subscribes only holds a connection: it goes after a while.
  for (const auto& s : sessions_) {
    if (s->unsubscribed_for_s(now) <= opts_.subscribe_within_s) continue;
    ++counts_.idle_closed;
    log_once("idle", "view: closed a WebSocket that subscribed to nothing for " +
                         std::to_string(static_cast<int>(opts_.subscribe_within_s)) + " s");
    s->close_session();
  }
  bool reset = false;
  ViewBatch b = playback_ ? playback_->advance(now, reset) : feed_.take();
  if (reset) {
    model_.reset();
    scene_ = SceneBuilder(scene_settings_);
  }
  model_.apply(b);

  bool want_view = false, want_samples = false, want_graph = false, want_events = false,
       want_scene = false;
  for (const auto& s : sessions_) {
    want_view |= s->subscribed(kViewChannel);
    want_samples |= s->subscribed(kSampleChannel);
    want_graph |= s->subscribed(kGraphChannel);
    want_events |= s->subscribed(kEventChannel);
    want_scene |= s->subscribed(kSceneChannel);
  }
  const std::uint64_t t_ns = sim_ns(model_.time_s());
  if (want_view) {
    // A frame when something changed, and a heartbeat each second so a page sees the server alive.
    std::shared_ptr<const std::string> frame, snap;
    if (!b.empty() || force_frame_ || now >= next_heartbeat_s_) {
      force_frame_ = false;
      frame =
          share(model_.frame_json(b, realtime_ns(), playback_ ? playback_->state_json() : "null"));
      next_heartbeat_s_ = now + 1.0;
    }
    for (const auto& s : sessions_) {
      if (!s->subscribed(kViewChannel)) continue;
      if (reset || s->stale()) {
        if (!s->has_room()) {
          ++counts_.frames_dropped;
          continue;
        }
        if (!snap) snap = share(snapshot());
        s->fresh();
        s->send_channel(kViewChannel, t_ns, snap);
      } else if (frame) {
        s->send_channel(kViewChannel, t_ns, frame);
      }
    }
  }
  auto publish = [&](std::uint32_t channel, const google::protobuf::Message& m, double t_s) {
    const auto payload = share(m.SerializeAsString());
    for (const auto& s : sessions_) s->send_channel(channel, sim_ns(t_s), payload);
  };
  // A replay's jump carries the run's whole past: the protobuf channels get only the newest.
  if (want_samples)
    for (const ViewSample& s : b.samples) publish(kSampleChannel, s.sample, s.sample.stamp_s());
  if (want_graph && !b.graphs.empty()) {
    const std::size_t from = reset ? b.graphs.size() - 1 : 0;
    for (std::size_t i = from; i < b.graphs.size(); ++i)
      publish(kGraphChannel, b.graphs[i], b.graphs[i].t_s());
  }
  if (want_events && !b.events.empty()) {
    const std::size_t from = reset ? b.events.size() - 1 : 0;
    for (std::size_t i = from; i < b.events.size(); ++i)
      publish(kEventChannel, b.events[i], b.events[i].t_s());
  }
  // The scene: the batch's newest samples (a frame carries one per agent) and its events, then one
  // SceneUpdate for its newest graph snapshot; each is the whole picture, so one a frame is enough.
  for (const ViewSample& s : b.samples) scene_.on_sample(s.sample);
  for (const records::Event& e : b.events) scene_.on_event(e);
  if (want_scene && !b.graphs.empty()) {
    const records::GraphSnapshot& g = b.graphs.back();
    const auto payload = share(scene_.scene_json(g));
    for (const auto& s : sessions_) s->send_channel(kSceneChannel, sim_ns(g.t_s()), payload);
  }
  const auto period = std::chrono::microseconds(
      static_cast<std::int64_t>(std::max(0.001, opts_.frame_period_s) * 1e6));
  ++ticks_;
  if (stopping_) return;
  timer_->expires_after(period);
  timer_->async_wait([this](beast::error_code e) {
    if (!e) tick();
  });
}

namespace {

struct StaticFile {
  const char* root;  // "page" or "node"
  const char* path;
  const char* type;
};

// The only files the server serves: nothing a request names reaches the file system otherwise.
const std::map<std::string, StaticFile>& static_files() {
  static const std::map<std::string, StaticFile> files = {
      {"/", {"page", "index.html", "text/html; charset=utf-8"}},
      {"/index.html", {"page", "index.html", "text/html; charset=utf-8"}},
      {"/view.js", {"page", "view.js", "text/javascript; charset=utf-8"}},
      {"/view.css", {"page", "view.css", "text/css; charset=utf-8"}},
      {"/lib/three.module.min.js",
       {"node", "three/build/three.module.min.js", "text/javascript; charset=utf-8"}},
      {"/lib/uPlot.esm.js", {"node", "uplot/dist/uPlot.esm.js", "text/javascript; charset=utf-8"}},
      {"/lib/uPlot.min.css", {"node", "uplot/dist/uPlot.min.css", "text/css; charset=utf-8"}},
  };
  return files;
}

}  // namespace

ViewServer::Impl::HttpReply ViewServer::Impl::serve_http(
    const std::string& target_in, const http::request<http::empty_body>& req) {
  const std::string target = target_in.substr(0, target_in.find('?'));
  auto text = [&](http::status st, std::string body, const char* type) {
    http::response<http::string_body> res{st, req.version()};
    res.set(http::field::server, "quadswarm view");
    res.set(http::field::content_type, type);
    res.set(http::field::cache_control, "no-store");
    res.keep_alive(req.keep_alive());
    res.body() = std::move(body);
    res.prepare_payload();
    return HttpReply(std::move(res));
  };
  if (req.method() != http::verb::get && req.method() != http::verb::head) {
    return text(http::status::method_not_allowed, "the view is read-only: GET only\n",
                "text/plain");
  }
  if (target == "/stats") {
    return text(http::status::ok, counts().json() + "\n", "application/json");
  }
  if (target == "/favicon.ico") return text(http::status::no_content, "", "text/plain");
  const auto it = static_files().find(target);
  if (it == static_files().end()) {
    ++counts_.not_found;
    return text(http::status::not_found, "not found\n", "text/plain");
  }
  const std::filesystem::path path =
      std::filesystem::path(std::string(it->second.root) == "page" ? opts_.page_dir
                                                                   : opts_.node_modules) /
      it->second.path;
  http::file_body::value_type body;
  beast::error_code ec;
  body.open(path.c_str(), beast::file_mode::scan, ec);
  if (ec) {
    ++counts_.not_found;
    return text(http::status::not_found,
                path.string() + " is missing" +
                    (std::string(it->second.root) == "node"
                         ? ": the page's libraries come from npm; run tools/setup.sh\n"
                         : "\n"),
                "text/plain");
  }
  const auto size = body.size();
  http::response<http::file_body> res{std::piecewise_construct, std::make_tuple(std::move(body)),
                                      std::make_tuple(http::status::ok, req.version())};
  res.set(http::field::server, "quadswarm view");
  res.set(http::field::content_type, it->second.type);
  res.content_length(size);
  res.keep_alive(req.keep_alive());
  if (req.method() == http::verb::head) {
    http::response<http::empty_body> head{http::status::ok, req.version()};
    head.set(http::field::content_type, it->second.type);
    head.content_length(size);
    head.keep_alive(req.keep_alive());
    return HttpReply(std::move(head));
  }
  return HttpReply(std::move(res));
}

ViewServer::ViewServer(ViewServerOptions opts, ViewFeed& feed, std::string run_info,
                       SceneSettings scene, ViewPlayback* playback)
    : impl_(std::make_unique<Impl>(std::move(opts), feed, std::move(run_info), std::move(scene),
                                   playback)) {}

ViewServer::~ViewServer() { stop(); }

void ViewServer::start() { impl_->start(); }

void ViewServer::flush(double timeout_s) {
  if (!impl_->started_) return;
  const auto until = std::chrono::steady_clock::now() +
                     std::chrono::microseconds(static_cast<std::int64_t>(timeout_s * 1e6));
  const std::uint64_t from = impl_->ticks_;
  while (std::chrono::steady_clock::now() < until &&
         (impl_->ticks_ < from + 2 || impl_->queued_ > 0))
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
}
void ViewServer::stop() { impl_->stop(); }
std::uint16_t ViewServer::port() const { return impl_->port_; }

std::string ViewServer::url() const {
  const std::string& a = impl_->opts_.address;
  const std::string host = a == "0.0.0.0"                     ? "127.0.0.1"
                           : a.find(':') != std::string::npos ? "[" + a + "]"
                                                              : a;
  return "http://" + host + ":" + std::to_string(impl_->port_) + "/";
}

ViewCounts ViewServer::counts() const { return impl_->counts(); }

ViewCounts ViewServer::Impl::counts() const {
  const Counters& k = counts_;
  ViewCounts c;
#define QSWARM_VIEW_COUNT_COPY(name) c.name = k.name;
  QSWARM_VIEW_COUNTERS(QSWARM_VIEW_COUNT_COPY)
#undef QSWARM_VIEW_COUNT_COPY
  return c;
}

const std::vector<FoxgloveChannel>& ViewServer::channels() const { return impl_->channels_; }

}  // namespace qswarm
