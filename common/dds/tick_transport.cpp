#include "common/dds/tick_transport.hpp"

#include <arpa/inet.h>
#include <fastdds/rtps/transport/ChainingTransport.h>
#include <fastdds/rtps/transport/ChainingTransportDescriptor.h>
#include <fastdds/rtps/transport/TransportReceiverInterface.h>
#include <fastrtps/utils/IPLocator.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <set>
#include <utility>

#include "common/transport/port_plan.hpp"

namespace qswarm {

namespace rtps = eprosima::fastdds::rtps;
using eprosima::fastrtps::rtps::IPLocator;
using eprosima::fastrtps::rtps::Locator_t;

namespace {
// Datagrams read per recvmmsg.
constexpr std::size_t kBatch = 16;
// Batches a drain reads from one socket at most: a drain ends even while datagrams keep coming
// (a backlog after a stop, a flood), and what is left waits for the next one; 512 datagrams, above
// what a tick brings from the 128 agents the plan has receive at the tick, and about 10 ms of work.
constexpr int kBatchesPerDrain = 32;

bool every_interface(const std::string& interface) {
  return interface.empty() || interface == "0.0.0.0";
}

in_addr ipv4(const std::string& text) {
  in_addr a{};
  if (::inet_pton(AF_INET, text.c_str(), &a) != 1) a.s_addr = htonl(INADDR_ANY);
  return a;
}
}  // namespace

// One bound socket and where its datagrams go.
struct TickReceive::Channel {
  int fd = -1;
  std::uint16_t port = 0;
  Locator_t locator;  // as Fast DDS opened it: the local locator of what arrives
  rtps::TransportReceiverInterface* receiver = nullptr;
  std::uint32_t max_size = 0;
  ~Channel() {
    if (fd >= 0) ::close(fd);
  }
};

TickReceive::TickReceive(std::string interface, int receive_buffer_bytes)
    : interface_(std::move(interface)), buffer_bytes_(receive_buffer_bytes) {}

TickReceive::~TickReceive() = default;

std::shared_ptr<TickReceive::Channel> TickReceive::bind_channel(
    const Locator_t& locator, rtps::TransportReceiverInterface* rx, std::uint32_t max_size) {
  auto c = std::make_shared<Channel>();
  c->port = IPLocator::getPhysicalPort(locator);
  c->locator = locator;
  c->receiver = rx;
  c->max_size = max_size;
  c->fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (c->fd < 0) return nullptr;
  // Where the kernel allows it (root), past rmem_max: it holds what arrives between two drains.
  if (::setsockopt(c->fd, SOL_SOCKET, SO_RCVBUFFORCE, &buffer_bytes_, sizeof buffer_bytes_) != 0)
    ::setsockopt(c->fd, SOL_SOCKET, SO_RCVBUF, &buffer_bytes_, sizeof buffer_bytes_);
  sockaddr_in at{};
  at.sin_family = AF_INET;
  at.sin_port = htons(c->port);
  const bool multicast = IPLocator::isMulticast(locator);
  if (multicast) {
    // As Fast DDS binds a multicast port: shared with every participant of the host. Bound to
    // the group itself, so it hears that group alone.
    const int one = 1;
    ::setsockopt(c->fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    at.sin_addr = ipv4(IPLocator::toIPv4string(locator));
  } else {
    at.sin_addr = ipv4(every_interface(interface_) ? "0.0.0.0" : interface_);
  }
  if (::bind(c->fd, reinterpret_cast<const sockaddr*>(&at), sizeof at) != 0) return nullptr;
  if (multicast) {
    std::vector<std::string> on;
    if (every_interface(interface_)) {
      const std::set<std::string> here = local_ipv4_addresses();
      on.assign(here.begin(), here.end());
    } else {
      on.push_back(interface_);
    }
    bool joined = false;
    for (const std::string& address : on) {
      ip_mreq m{};
      m.imr_multiaddr = at.sin_addr;
      m.imr_interface = ipv4(address);
      joined |= ::setsockopt(c->fd, IPPROTO_IP, IP_ADD_MEMBERSHIP, &m, sizeof m) == 0;
    }
    if (!joined) return nullptr;
  }
  return c;
}

bool TickReceive::open(const Locator_t& locator, rtps::TransportReceiverInterface* receiver,
                       std::uint32_t max_size) {
  const std::lock_guard<std::recursive_mutex> lock(mu_);
  // As Fast DDS's UDPv4, a port opens once; Fast DDS asks is_open (by port) before it opens one.
  if (is_open(locator)) return false;
  auto c = bind_channel(locator, receiver, max_size);
  if (!c) return false;
  channels_.push_back(std::move(c));
  return true;
}

bool TickReceive::close(const Locator_t& locator) {
  const std::lock_guard<std::recursive_mutex> lock(mu_);
  const std::uint16_t port = IPLocator::getPhysicalPort(locator);
  const auto before = channels_.size();
  channels_.erase(std::remove_if(channels_.begin(), channels_.end(),
                                 [&](const auto& c) { return c->port == port; }),
                  channels_.end());
  return channels_.size() != before;
}

bool TickReceive::is_open(const Locator_t& locator) const {
  const std::lock_guard<std::recursive_mutex> lock(mu_);
  const std::uint16_t port = IPLocator::getPhysicalPort(locator);
  return std::any_of(channels_.begin(), channels_.end(),
                     [&](const auto& c) { return c->port == port; });
}

std::vector<int> TickReceive::fds() const {
  const std::lock_guard<std::recursive_mutex> lock(mu_);
  std::vector<int> out;
  for (const auto& c : channels_) out.push_back(c->fd);
  return out;
}

TickReceive::Counters TickReceive::counters() const {
  const std::lock_guard<std::recursive_mutex> lock(mu_);
  return counters_;
}

std::size_t TickReceive::drain() {
  const std::lock_guard<std::recursive_mutex> lock(mu_);
  ++counters_.drains;
  // A listener run from here may open or close channels: walk a copy, each kept alive by it.
  const std::vector<std::shared_ptr<Channel>> channels = channels_;
  std::size_t got = 0;
  for (const auto& c : channels) {
    if (std::find(channels_.begin(), channels_.end(), c) == channels_.end()) continue;  // closed
    const std::size_t slot = std::max<std::uint32_t>(c->max_size, 1);
    if (buffer_.size() < slot * kBatch) buffer_.resize(slot * kBatch);
    for (int batch = 0; batch < kBatchesPerDrain; ++batch) {
      mmsghdr msgs[kBatch] = {};
      iovec iov[kBatch];
      sockaddr_in from[kBatch];
      for (std::size_t i = 0; i < kBatch; ++i) {
        iov[i].iov_base = buffer_.data() + i * slot;
        iov[i].iov_len = slot;
        msgs[i].msg_hdr.msg_iov = &iov[i];
        msgs[i].msg_hdr.msg_iovlen = 1;
        msgs[i].msg_hdr.msg_name = &from[i];
        msgs[i].msg_hdr.msg_namelen = sizeof from[i];
      }
      const int n = ::recvmmsg(c->fd, msgs, kBatch, MSG_DONTWAIT, nullptr);
      if (n < 0) {
        if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) ++counters_.errors;
        break;
      }
      for (int i = 0; i < n; ++i) {
        // Closed by a listener meanwhile: its receiver may be gone.
        if (std::find(channels_.begin(), channels_.end(), c) == channels_.end()) return got;
        if (msgs[i].msg_hdr.msg_flags & MSG_TRUNC) {
          ++counters_.truncated;
          continue;
        }
        Locator_t remote;
        remote.kind = LOCATOR_KIND_UDPv4;
        IPLocator::setIPv4(remote,
                           reinterpret_cast<const unsigned char*>(&from[i].sin_addr.s_addr));
        remote.port = ntohs(from[i].sin_port);
        ++counters_.datagrams;
        counters_.bytes += msgs[i].msg_len;
        ++got;
        c->receiver->OnDataReceived(buffer_.data() + static_cast<std::size_t>(i) * slot,
                                    msgs[i].msg_len, c->locator, remote);
      }
      if (n < static_cast<int>(kBatch)) break;
    }
  }
  return got;
}

namespace {

class TickTransport final : public rtps::ChainingTransport {
 public:
  TickTransport(const rtps::ChainingTransportDescriptor& d, std::shared_ptr<TickReceive> rx,
                rtps::TransportDescriptorInterface* self)
      : ChainingTransport(d), rx_(std::move(rx)), self_(self) {}

  bool OpenInputChannel(const Locator_t& locator, rtps::TransportReceiverInterface* receiver,
                        uint32_t max_message_size) override {
    if (!IsLocatorSupported(locator) || !is_locator_allowed(locator)) return false;
    return rx_->open(locator, receiver, max_message_size);
  }
  bool CloseInputChannel(const Locator_t& locator) override { return rx_->close(locator); }
  bool IsInputChannelOpen(const Locator_t& locator) const override {
    return IsLocatorSupported(locator) && rx_->is_open(locator);
  }
  rtps::TransportDescriptorInterface* get_configuration() override { return self_; }

  bool send(eprosima::fastrtps::rtps::SenderResource* low,
            const eprosima::fastrtps::rtps::octet* buffer, uint32_t size,
            eprosima::fastrtps::rtps::LocatorsIterator* begin,
            eprosima::fastrtps::rtps::LocatorsIterator* end,
            const std::chrono::steady_clock::time_point& timeout) override {
    return low->send(buffer, size, begin, end, timeout);
  }
  // Nothing arrives through the lower transport: it opens no input channel.
  void receive(rtps::TransportReceiverInterface* next, const eprosima::fastrtps::rtps::octet* data,
               uint32_t size, const Locator_t& local, const Locator_t& remote) override {
    next->OnDataReceived(data, size, local, remote);
  }

 private:
  std::shared_ptr<TickReceive> rx_;
  rtps::TransportDescriptorInterface* self_;
};

struct TickTransportDescriptor final : public rtps::ChainingTransportDescriptor {
  TickTransportDescriptor(std::shared_ptr<rtps::TransportDescriptorInterface> low,
                          std::shared_ptr<TickReceive> r)
      : ChainingTransportDescriptor(std::move(low)), rx(std::move(r)) {}
  rtps::TransportInterface* create_transport() const override {
    return new TickTransport(*this, rx, const_cast<TickTransportDescriptor*>(this));
  }
  std::shared_ptr<TickReceive> rx;
};

}  // namespace

std::shared_ptr<rtps::TransportDescriptorInterface> tick_transport(
    std::shared_ptr<rtps::TransportDescriptorInterface> low_level,
    std::shared_ptr<TickReceive> rx) {
  return std::make_shared<TickTransportDescriptor>(std::move(low_level), std::move(rx));
}

}  // namespace qswarm
