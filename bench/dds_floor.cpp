// The middleware's floor under an agent of an all-to-all swarm: N processes, each one DDS
// participant made as an agent's is (DdsParticipant: loopback UDP, the port plan, Fast DDS's
// threads at nice 15) with one best-effort writer and one reader of the agents' state topic, and
// nothing else: no simulation, no law, no gate, no record stream. Once all have matched, each
// writes one AgentState at RATE_HZ on one shared time grid (carrying ENTRIES flow entries, as an
// edge-flow agent of degree N - 1 does) and its reader's listener takes every sample into a
// reused one. The readers listen on unicast ports or, like delivery ALL, on one multicast group.
// Reports each process's CPU over the flight (median, max), late ticks, samples received per
// process per second and CPU per received sample: what an agent costs beyond this is the
// project's, not Fast DDS's or the kernel's (bench/wire_floor.cpp is the kernel's floor).
// Usage: dds_floor N [SECONDS=20] [RATE_HZ=50] [multicast|unicast] [ENTRIES=N-1] [DOMAIN=20]
//        [threads|tick] (Fast DDS's receive threads, or the sockets drained after each wait)
#include <sys/mman.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include <fastrtps/utils/IPLocator.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include "bench/process_bench.hpp"
#include "common/dds/participant.hpp"
#include "common/dds/qos.hpp"
#include "common/dds/tick_transport.hpp"
#include "common/transport/port_plan.hpp"
#include "swarm_statePubSubTypes.h"

namespace {

namespace dds = eprosima::fastdds::dds;

using qswarm::bench::cpu_s;
using qswarm::bench::now_s;
using qswarm::bench::sleep_until;

// Shared by the processes (an anonymous mapping made before they fork).
struct Shared {
  std::atomic<int> matched{0};      // processes whose reader has matched every writer
  std::atomic<double> start{0.0};   // the flight's first tick, once everyone matched
  std::atomic<bool> failed{false};  // a process could not start: nobody flies
};

struct Result {
  double cpu_s = 0.0;
  long ticks = 0, late = 0, received = 0;
  bool matched = false;
};

struct Counter : public dds::DataReaderListener {
  std::uint32_t self = 0;
  std::atomic<long> received{0};
  qswarm_msgs::AgentState s;  // reused, as a reader that allocates nothing per sample would
  void on_data_available(dds::DataReader* r) override {
    dds::SampleInfo info;
    while (r->take_next_sample(&s, &info) == ReturnCode_t::RETCODE_OK)
      if (info.valid_data && s.id() != self) ++received;
  }
};

Result fly(int i, int n, double seconds, double hz, bool multicast, int entries,
           std::uint32_t domain, bool tick, Shared& shared) {
  Counter counter;  // the reader's listener: it outlives the participant
  counter.self = static_cast<std::uint32_t>(i + 1);
  qswarm::ParticipantOptions po;
  po.domain_id = domain;
  po.name = "dds-floor-" + std::to_string(i + 1);
  po.participant_id = i;
  po.threads_nice = 15;
  po.tick_receive = tick;
  qswarm::DdsParticipant participant(po);
  // With the receive at the tick, this thread reads the sockets after each wait, as an agent does.
  const auto drain = [&] {
    if (qswarm::TickReceive* rx = participant.tick_receive()) rx->drain();
  };
  dds::DomainParticipant* p = participant.get();
  dds::TypeSupport type(new qswarm_msgs::AgentStatePubSubType());
  type.register_type(p);
  dds::Topic* topic =
      p->create_topic("qswarm/agent_state", type.get_type_name(), dds::TOPIC_QOS_DEFAULT);
  dds::Publisher* pub = p->create_publisher(dds::PUBLISHER_QOS_DEFAULT);
  dds::Subscriber* sub = p->create_subscriber(dds::SUBSCRIBER_QOS_DEFAULT);
  dds::DataWriterQos wq = qswarm::best_effort_writer_qos();
  wq.endpoint().history_memory_policy =
      eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  dds::DataWriter* writer = pub->create_datawriter(topic, wq);
  dds::DataReaderQos rq = qswarm::best_effort_reader_qos();
  rq.resource_limits().max_instances = n + 16;
  rq.resource_limits().max_samples_per_instance = 1;
  rq.resource_limits().max_samples = n + 16;
  rq.resource_limits().allocated_samples = 32;
  rq.endpoint().history_memory_policy =
      eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  if (multicast) {
    eprosima::fastrtps::rtps::Locator_t group;
    eprosima::fastrtps::rtps::IPLocator::setIPv4(group, "239.255.190.1");
    group.port = qswarm::PortPlan::data_multicast_port(domain);
    rq.endpoint().multicast_locator_list.push_back(group);
  }
  dds::DataReader* reader = sub->create_datareader(topic, rq, &counter);
  Result r;
  if (!writer || !reader) return r;

  qswarm_msgs::AgentState out;
  out.id(counter.self);
  out.consensus({1.0, 2.0, 3.0});
  out.position({1.0, 2.0, 3.0});
  for (int e = 0; e < entries; ++e) {
    qswarm_msgs::FlowEntry f;
    f.peer(static_cast<std::uint32_t>(e + 1));
    f.flow({0.1, 0.2, 0.3});
    f.weight(1.0);
    f.active(true);
    out.flows().push_back(f);
  }
  // Matched: every other process's writer (and its own).
  const double give_up = now_s() + 120.0;
  dds::SubscriptionMatchedStatus st;
  while (now_s() < give_up && !shared.failed) {
    reader->get_subscription_matched_status(st);
    if (st.current_count >= n) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    drain();
  }
  r.matched = st.current_count >= n;
  if (shared.matched.fetch_add(1) + 1 == n) shared.start = std::ceil(now_s()) + 1.0;
  while (shared.start.load() == 0.0 && !shared.failed && now_s() < give_up + 10.0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    drain();
  }
  const double start = shared.start.load();
  if (start == 0.0) {
    r.matched = false;  // the others never all matched: this process did not fly
    return r;
  }

  const double period = 1.0 / hz;
  sleep_until(start);
  const long before = counter.received;
  const double cpu0 = cpu_s();
  for (long k = 0; static_cast<double>(k) * period < seconds; ++k) {
    const double due = start + static_cast<double>(k) * period;
    sleep_until(due);
    drain();
    if (now_s() - due > period) ++r.late;
    ++r.ticks;
    out.seq(static_cast<std::uint64_t>(k));
    writer->write(&out);
  }
  r.cpu_s = cpu_s() - cpu0;
  r.received = counter.received - before;
  return r;  // the participant deletes its entities; the listener outlives it
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: dds_floor N [SECONDS=20] [RATE_HZ=50] [multicast|unicast] "
                 "[ENTRIES=N-1] [DOMAIN=20] [threads|tick]\n");
    return 2;
  }
  const int n = std::atoi(argv[1]);
  const double seconds = argc > 2 ? std::atof(argv[2]) : 20.0;
  const double hz = argc > 3 ? std::atof(argv[3]) : 50.0;
  const std::string mode = argc > 4 ? argv[4] : "multicast";
  const int entries = argc > 5 ? std::atoi(argv[5]) : n - 1;
  const long domain = argc > 6 ? std::atol(argv[6]) : 20;
  const std::string receive = argc > 7 ? argv[7] : "threads";
  const char* bad = nullptr;
  if (n < 2 || n > 256) {
    bad = "N: 2 to 256 processes";
  } else if (!(seconds > 0.0 && seconds <= 3600.0)) {
    bad = "SECONDS: above 0, at most 3600";
  } else if (!(hz > 0.0 && hz <= 1000.0)) {
    bad = "RATE_HZ: above 0, at most 1000";
  } else if (mode != "multicast" && mode != "unicast") {
    bad = "the delivery: multicast or unicast";
  } else if (entries < 0 || entries > 511) {
    bad = "ENTRIES: 0 to 511";
  } else if (domain < 0 || domain > static_cast<long>(qswarm::PortPlan::kMaxDomain)) {
    bad = "DOMAIN: 0 to the port plan's largest domain";
  } else if (receive != "threads" && receive != "tick") {
    bad = "RECEIVE: threads or tick";
  }
  if (bad) {
    std::fprintf(stderr, "dds_floor: %s\n", bad);
    return 2;
  }
  void* mem =
      mmap(nullptr, sizeof(Shared), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
  if (mem == MAP_FAILED) return 1;
  Shared& shared = *new (mem) Shared();
  const std::vector<Result> all = qswarm::bench::in_processes<Result>(n, [&](int i) {
    try {
      return fly(i, n, seconds, hz, mode == "multicast", entries,
                 static_cast<std::uint32_t>(domain), receive == "tick", shared);
    } catch (const std::exception& e) {  // its ports taken (another run on DOMAIN), ...
      std::fprintf(stderr, "dds_floor: process %d: %s\n", i + 1, e.what());
      shared.failed = true;  // the others stop waiting for it
      return Result{};
    }
  });
  const long unmatched =
      std::count_if(all.begin(), all.end(), [](const Result& x) { return !x.matched; });
  if (static_cast<int>(all.size()) != n || unmatched > 0) {
    std::fprintf(
        stderr,
        "dds_floor: %zu of %d processes reported, %ld never matched everyone or never flew\n",
        all.size(), n, unmatched);
    return 1;
  }
  std::vector<double> cpu;
  long ticks = 0, late = 0, received = 0;
  double cpu_total = 0.0;
  for (const Result& x : all) {
    cpu.push_back(100.0 * x.cpu_s / seconds);
    cpu_total += x.cpu_s;
    ticks += x.ticks;
    late += x.late;
    received += x.received;
  }
  std::sort(cpu.begin(), cpu.end());
  std::printf("| %d | %s | %.0f | %d | %.2f | %.2f | %.2f | %.0f | %.1f |\n", n, mode.c_str(), hz,
              entries, cpu[cpu.size() / 2], cpu.back(),
              100.0 * static_cast<double>(late) / static_cast<double>(ticks),
              static_cast<double>(received) / seconds / n,
              received > 0 ? 1e6 * cpu_total / static_cast<double>(received) : 0.0);
  return 0;
}
