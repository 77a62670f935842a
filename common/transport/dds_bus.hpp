#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>

#include "common/transport/neighbor_bus.hpp"

namespace qswarm {

struct DdsOptions {
  std::uint32_t domain_id = 0;
  std::string participant_name = "qswarm";
  // DDS traffic stays on this interface (loopback by default: nothing leaves the host).
  std::string interface = "127.0.0.1";
  bool shared_memory = false;  // off by default: faults below the application must bite
  int max_agents = 512;        // sizes the keyed reader (Fast DDS defaults cap it at 10 instances)
  bool publish = true;         // false: a read-only participant (the supervisor)
  // Fast DDS's test transport instead of plain UDPv4: drop this percentage of data messages on
  // the sending side (0 = plain UDPv4).
  std::uint8_t test_drop_data_percent = 0;
};

struct BusCounters {
  std::uint64_t published = 0;
  std::uint64_t received = 0;  // accepted samples
  std::uint64_t dropped = 0;   // refused: invalid content
  std::uint64_t stale = 0;     // refused: not newer than what we hold
};

// The product's NeighborBus: one DomainParticipant, the keyed best-effort state topic
// "qswarm/agent_state", a keep-last-1 writer and reader. Incoming samples are checked in the
// listener: bad ones are dropped, counted and logged once per peer; nothing throws out of it.
class DdsBus final : public NeighborBus {
 public:
  using SampleCallback = std::function<void(const StateMessage&, std::int64_t recv_wall_ns)>;

  explicit DdsBus(const DdsOptions& opts);
  ~DdsBus() override;
  DdsBus(const DdsBus&) = delete;
  DdsBus& operator=(const DdsBus&) = delete;

  void publish(const StateMessage& msg) override;
  std::vector<StateMessage> latest(AgentId self) override;
  // Called for every accepted sample, on a DDS thread (set before samples flow).
  void set_sample_callback(SampleCallback cb);
  BusCounters counters() const;
  // Number of readers matched to our writer (DDS discovery; the start barrier waits on it).
  int matched_readers() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

std::int64_t wall_now_ns();

}  // namespace qswarm
