#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <fastdds/rtps/common/Locator.h>
#include <fastdds/rtps/transport/TransportDescriptorInterface.h>

#include "common/clock/clock.hpp"

namespace eprosima::fastdds::rtps {
class TransportReceiverInterface;
}  // namespace eprosima::fastdds::rtps

namespace qswarm {

// The receive side of a UDPv4 transport that no thread of its own reads: its sockets are
// non-blocking, and the thread that owns the process's loop reads them all at once (drain(), one
// recvmmsg per batch) and hands each datagram to Fast DDS there. Fast DDS 2.9.1's UDPv4 gives
// every input locator a thread blocked in recvfrom, so a burst of samples wakes threads; a sample
// newer than the last one only matters at the next tick, so reading at the tick loses nothing the
// law uses and the process wakes once a tick. Sending, locators and the test transport's drops
// stay Fast DDS's own (a chaining transport over them).
class TickReceive {
 public:
  struct Counters {
    std::uint64_t drains = 0;
    std::uint64_t datagrams = 0;
    std::uint64_t bytes = 0;
    std::uint64_t truncated = 0;  // larger than the channel's message size: dropped
    std::uint64_t errors = 0;     // a receive that failed (not "nothing waiting")
  };

  // `interface`: the IPv4 address the participant's traffic stays on ("" or "0.0.0.0": every
  // interface). `receive_buffer_bytes`: each socket's kernel buffer, which holds what arrives
  // between two drains.
  explicit TickReceive(std::string interface, int receive_buffer_bytes = 4 << 20);
  ~TickReceive();
  TickReceive(const TickReceive&) = delete;
  TickReceive& operator=(const TickReceive&) = delete;

  // Reads every datagram waiting on every input socket and gives each to its channel's receiver.
  // Returns how many. Call it from one thread (the loop's); Fast DDS's listeners run on it.
  std::size_t drain();
  Counters counters() const;
  // The descriptors of the sockets it reads, one per input locator Fast DDS opened.
  std::vector<int> fds() const;

  // The transport's side (Fast DDS calls these through it).
  bool open(const eprosima::fastrtps::rtps::Locator_t& locator,
            eprosima::fastdds::rtps::TransportReceiverInterface* receiver, std::uint32_t max_size);
  bool close(const eprosima::fastrtps::rtps::Locator_t& locator);
  bool is_open(const eprosima::fastrtps::rtps::Locator_t& locator) const;

 private:
  struct Channel;
  std::shared_ptr<Channel> bind_channel(const eprosima::fastrtps::rtps::Locator_t& locator,
                                        eprosima::fastdds::rtps::TransportReceiverInterface* rx,
                                        std::uint32_t max_size);
  const std::string interface_;
  const int buffer_bytes_;
  // Recursive: a listener that drain() runs may make an endpoint, which opens a channel.
  mutable std::recursive_mutex mu_;
  std::vector<std::shared_ptr<Channel>> channels_;
  std::vector<std::uint8_t> buffer_;  // the batch's datagrams, drain() only
  Counters counters_;
};

// A transport descriptor for a participant whose receive side `rx` drains: sends through
// `low_level` (Fast DDS's UDPv4 or its test transport), receives through `rx`.
std::shared_ptr<eprosima::fastdds::rtps::TransportDescriptorInterface> tick_transport(
    std::shared_ptr<eprosima::fastdds::rtps::TransportDescriptorInterface> low_level,
    std::shared_ptr<TickReceive> rx);

// The process's clock for a loop that reads its participant at the tick: every wait on it ends
// with a drain, so the loop acts on what arrived while it slept, and its thread wakes once a wait.
// (Waking for each arrival before flight as well was tried: at 32 agents discovery took 3.3 s
// against 2.4 to 2.5, and at 256 it changed nothing.)
class DrainingClock final : public Clock {
 public:
  // What to drain after each wait (null: nothing, a plain SteadyClock).
  void drain(TickReceive* rx) { rx_ = rx; }
  double now_s() const override { return base_.now_s(); }
  std::int64_t wall_ns() const override { return base_.wall_ns(); }
  void sleep_until(double t_s) override {
    base_.sleep_until(t_s);
    if (rx_ != nullptr) rx_->drain();
  }
  double shared_origin_s() const override { return base_.shared_origin_s(); }

 private:
  SteadyClock base_;
  TickReceive* rx_ = nullptr;
};

}  // namespace qswarm
