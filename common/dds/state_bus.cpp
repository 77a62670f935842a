// The product's NeighborBus over DDS: the topics, the record stream, the readers' settings and
// what is admitted of what they read. Where the state stream's endpoints are and how they move is
// the routing's (state_routes.hpp).
#include "common/dds/state_bus.hpp"

#include <fastrtps/utils/IPLocator.h>
#include <spdlog/spdlog.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <mutex>
#include <optional>
#include <stdexcept>

#include "common/dds/idl_convert.hpp"
#include "common/dds/qos.hpp"
#include "common/dds/roster_filter.hpp"
#include "common/dds/state_routes.hpp"
#include "common/dds/writer_registry.hpp"
#include "common/transport/dds_names.hpp"
#include "common/transport/port_plan.hpp"
#include "common/transport/sample_gate.hpp"

#include "swarm_statePubSubTypes.h"

namespace qswarm {

namespace dds = eprosima::fastdds::dds;
using state_bus::Reader;
using state_bus::Writer;

struct DdsStateBus::Impl : public dds::DataReaderListener {
  StateBusOptions opts;
  std::string multicast_group;   // the group its readers listen on ("" : unicast)
  const Clock* clock = nullptr;  // the receiver's wall time, for the gate
  dds::DomainParticipant* participant = nullptr;
  dds::TypeSupport type{new qswarm_msgs::AgentStatePubSubType()};
  dds::Topic* topic = nullptr;                   // the state stream's shared topic: agent to agent
  dds::Topic* record_topic = nullptr;            // agent to supervisor
  RosterFilterFactory roster_factory;            // outlives the filtered topics
  Writer record_writer;                          // an agent's records, bound to it
  dds::Subscriber* record_subscriber = nullptr;  // the supervisor's
  Reader record_reader;
  std::unique_ptr<state_bus::StateEndpoints> endpoints;
  std::unique_ptr<state_bus::StateRoute> route;  // the state stream's (not the supervisor's)

  const WriterRegistry* writers = nullptr;
  bool bind = false;  // a secure participant: samples only from writers bound to their key
  std::array<std::uint8_t, 12> own_prefix{};  // our participant's GUID prefix

  mutable std::mutex mu;  // the gate, and what follows
  SampleGate gate;
  std::set<std::uint64_t> warned_writers;  // refused for their binding, logged once
  static constexpr std::size_t kWritersWarned = 1024;
  static constexpr int kOwnerChangesLogged = 3;
  std::map<AgentId, int> owner_changes_logged;
  // Held while the listener runs and while it is replaced: once set_listener returns, the old
  // listener is neither running nor called again (the agent's decorator unregisters this way
  // before it is destroyed, while DDS threads still deliver).
  std::mutex listener_mu;
  Listener listener;
  qswarm_msgs::AgentState out_sample;  // reused: publishing allocates nothing in steady state

  // The state readers' settings: sized for the swarm, and on the run's multicast group if asked.
  dds::DataReaderQos reader_qos(DdsParticipant& participant);
  // Deletes every endpoint and topic it made, before the participant is: the readers' listener is
  // this object, and the filter's factory lives in it.
  void close();
  // Its endpoints: the record stream's writer or reader, and the state stream's route.
  void open();

  void on_data_available(dds::DataReader* r) override {
    try {
      // Each receive thread decodes into storage of its own, reused from sample to sample: the
      // lists of a sample (flows, copies) then allocate nothing once they have grown. Shared by
      // every reader on the thread: a listener that published (a same-thread delivery to
      // another reader of this process) would overwrite it; none does, and every one copies.
      thread_local qswarm_msgs::AgentState s;
      thread_local StateMessage m;
      dds::SampleInfo info;
      while (r->take_next_sample(&s, &info) == ReturnCode_t::RETCODE_OK) {
        if (!info.valid_data) continue;
        WriterId w;  // the publication handle is the writer's GUID
        std::memcpy(w.bytes.data(), info.publication_handle.value, w.bytes.size());
        // With a writer per name, an agent speaks through several writers, and through new ones
        // as it moves between cells: the gate judges its participant (a copy heard through two
        // names is then stale, and a move is no change of owner).
        if (opts.routing != Routing::kPartitions)
          std::fill(w.bytes.begin() + 12, w.bytes.end(), std::uint8_t{0});
        from_idl(s, m);
        accept(m, w);
      }
    } catch (const std::exception& e) {
      spdlog::error("dds: listener caught: {}", e.what());
    } catch (...) {
      spdlog::error("dds: listener caught an unknown exception");
    }
  }

  bool own(const WriterId& w) const {
    return std::memcmp(w.bytes.data(), own_prefix.data(), own_prefix.size()) == 0;
  }

  // Under DDS-Security: whether the writer is bound to the agent the sample is keyed as; if not,
  // the sample is refused, counted, named (kBoundElsewhere) and logged once per writer.
  bool bound(const StateMessage& m, const WriterId& w) {
    if (!bind || own(w)) return true;
    const WriterRegistry::Binding b = writers->binding(w);
    if (b.agent && *b.agent == m.view.id) return true;
    std::string bound_to = "no agent";
    if (b.pattern) {
      bound_to = "no agent (it publishes into a partition pattern)";
    } else if (b.changed) {
      bound_to = "no agent any more (its partitions changed)";
    } else if (b.agent) {
      bound_to = "agent " + std::to_string(*b.agent);
    } else if (!b.known) {
      bound_to = "nothing yet (not discovered)";
    }
    bool first = false;
    {
      std::lock_guard<std::mutex> lock(mu);
      ++gate.counters().dropped;
      // A writer not yet discovered is a race, not a forgery (its binding comes with discovery).
      if (b.known) gate.notice(m.view.id, kBoundElsewhere);
      first = warned_writers.size() < kWritersWarned && warned_writers.insert(w.hash()).second;
    }
    if (first)
      spdlog::warn(
          "refused samples keyed as agent {} from writer {}, which its certificate binds to {} "
          "(further refusals are counted, not logged)",
          m.view.id, w.str(), bound_to);
    return false;
  }

  void accept(const StateMessage& m, const WriterId& w) {
    if (!bound(m, w)) return;
    const std::string why = check_message(m);  // pure: outside the lock the agent's tick takes
    SampleGate::Result r;
    int owner_changes = 0;  // logged before this one
    {
      std::lock_guard<std::mutex> lock(mu);
      r = gate.admit(m, why, clock->wall_ns(), w);
      if (r.new_owner) owner_changes = owner_changes_logged[m.view.id]++;
    }
    for (const SuspectKind k : {kTwoWriters, kSequenceJump, kFutureIncarnation}) {
      if ((r.noticed & k) == 0) continue;
      spdlog::warn("agent {}: {} (writer {}, seq {}); named in the record", m.view.id,
                   suspect_text(k), w.str(), m.seq);
    }
    // A forger can make the agent change hands at its own rate: a few lines per agent, then
    // silence (the gate's counters and the record's forgeries keep the rest).
    if (r.new_owner && owner_changes < kOwnerChangesLogged)
      spdlog::info(
          "agent {}: now heard from writer {} (the writer heard before went silent){}", m.view.id,
          w.str(),
          owner_changes + 1 == kOwnerChangesLogged ? "; further changes are not logged" : "");
    if (r.verdict == SampleGate::Verdict::kForeign && r.first_from) {
      spdlog::warn("samples of another run (run id {:x}) on this domain: dropped and counted",
                   m.run_id);
    }
    if (r.verdict == SampleGate::Verdict::kInvalid && r.first_from) {
      spdlog::warn(
          "dropped a sample from agent {}: {} (further drops from it are counted, not logged)",
          m.view.id, r.why);
    }
    if (r.verdict != SampleGate::Verdict::kAccepted) return;
    std::lock_guard<std::mutex> lock(listener_mu);
    if (listener) listener(m);
  }
};

DdsStateBus::DdsStateBus(DdsParticipant& participant, const StateBusOptions& opts,
                         const Clock& clock)
    : impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  d.opts = opts;
  d.clock = &clock;
  d.gate = SampleGate(opts.run_id, opts.law);
  d.participant = participant.get();
  d.writers = &participant.writers();
  d.bind = participant.secure();
  std::memcpy(d.own_prefix.data(), d.participant->guid().guidPrefix.value, d.own_prefix.size());
  d.type.register_type(d.participant);
  d.topic = d.participant->create_topic(dds_names::kStateTopic, d.type.get_type_name(),
                                        dds::TOPIC_QOS_DEFAULT);
  d.record_topic = d.participant->create_topic(dds_names::kRecordTopic, d.type.get_type_name(),
                                               dds::TOPIC_QOS_DEFAULT);
  if (!d.topic || !d.record_topic) {
    d.close();
    throw std::runtime_error("dds: cannot create the state topics");
  }
  std::memcpy(d.roster_factory.local.data(), d.own_prefix.data(), d.own_prefix.size());
  if (!opts.roster.empty())
    d.participant->register_content_filter_factory(RosterFilterFactory::kRosterFilterClass,
                                                   &d.roster_factory);
  try {
    d.endpoints = std::make_unique<state_bus::StateEndpoints>(
        d.participant, opts, d.type.get_type_name(), d.topic, &d, d.roster_factory,
        d.reader_qos(participant));
    d.open();
  } catch (...) {
    d.close();
    throw;
  }
}

void DdsStateBus::Impl::open() {
  state_bus::StateEndpoints& e = *endpoints;
  if (opts.publish) {
    // Its records in the run's record partition and its agent's under it (which binds them).
    dds::PublisherQos q = dds::PUBLISHER_QOS_DEFAULT;
    const std::string records = dds_names::record_partition(opts.run_id);
    q.partition().push_back(records.c_str());
    if (opts.self != 0)
      q.partition().push_back(dds_names::bound_partition(records, opts.self).c_str());
    record_writer.publisher = participant->create_publisher(q);
    record_writer.listener = std::make_unique<state_bus::WriterListener>();
    record_writer.writer = record_writer.publisher
                               ? record_writer.publisher->create_datawriter(
                                     record_topic, state_bus::unfiltered(record_writer_qos()),
                                     record_writer.listener.get())
                               : nullptr;
    if (!record_writer.writer) throw std::runtime_error("dds: cannot create the record writer");
  }
  if (opts.recorder) {
    dds::SubscriberQos q = dds::SUBSCRIBER_QOS_DEFAULT;
    const std::string part = opts.hear_all_runs
                                 ? dds_names::any_run_partition(dds_names::kRecordStream)
                                 : dds_names::record_partition(opts.run_id);
    q.partition().push_back(part.c_str());
    record_subscriber = participant->create_subscriber(q);
    if (!record_subscriber) throw std::runtime_error("dds: cannot create the record subscriber");
    record_reader = e.make_reader(record_subscriber, record_topic);
    return;
  }
  route = opts.routing == Routing::kPartitions
              ? state_bus::partitions_route(e)
              : state_bus::named_route(e, opts.routing == Routing::kRegionTopics);
}

dds::DataReaderQos DdsStateBus::Impl::reader_qos(DdsParticipant& p) {
  dds::DataReaderQos rq = opts.recorder ? record_reader_qos() : best_effort_reader_qos();
  rq.resource_limits().max_instances = opts.max_agents + 16;
  rq.resource_limits().max_samples_per_instance = 1;
  rq.resource_limits().max_samples = opts.max_agents + 16;
  // Reserved at creation, grown when needed: a state reader is one of up to 8 (one per region
  // topic), each with a pool of its own, and its listener takes what arrives at once.
  rq.resource_limits().allocated_samples = opts.recorder ? 32 : 4;
  rq.endpoint().history_memory_policy =
      eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  if (opts.recorder || opts.multicast_group.empty()) return rq;
  namespace rtps = eprosima::fastrtps::rtps;
  rtps::Locator_t group;
  if (p.options().interface.empty() || !rtps::IPLocator::setIPv4(group, opts.multicast_group) ||
      !rtps::IPLocator::isMulticast(group))
    throw std::invalid_argument("dds: a multicast state reader needs an IPv4 group (not \"" +
                                opts.multicast_group + "\") and one interface address");
  group.port = PortPlan::data_multicast_port(p.options().domain_id);
  // Fast DDS only logs a group socket it could not bind, and a reader listening on the group
  // alone would then hear nothing: a program holding the port alone leaves this reader on
  // unicast instead, and says so.
  if (const std::string problem =
          multicast_port_problem(opts.multicast_group, group.port, p.options().interface);
      !problem.empty()) {
    spdlog::warn("dds: state samples by unicast, not multicast group {}: {}", opts.multicast_group,
                 problem);
    return rq;
  }
  // The group alone, no unicast locator: a writer then always sends this reader's samples to the
  // group. With both, Fast DDS 2.9.1 aborts on a destination it first saw as part of a group
  // once the reader is the last one left in it (docs/fast-dds-workarounds.md, W4).
  rq.endpoint().multicast_locator_list.push_back(group);
  multicast_group = opts.multicast_group;
  spdlog::info("dds: state samples by multicast group {} port {}", multicast_group, group.port);
  return rq;
}

DdsStateBus::~DdsStateBus() {
  set_listener(nullptr);
  impl_->close();
}

void DdsStateBus::Impl::close() {
  route.reset();
  if (record_subscriber) {
    endpoints->delete_reader(record_subscriber, record_reader);
    participant->delete_subscriber(record_subscriber);
    record_subscriber = nullptr;
  }
  if (endpoints) endpoints->delete_writer(record_writer);
  if (!opts.roster.empty())
    participant->unregister_content_filter_factory(RosterFilterFactory::kRosterFilterClass);
  if (topic) participant->delete_topic(topic);
  if (record_topic) participant->delete_topic(record_topic);
  topic = record_topic = nullptr;
}

void DdsStateBus::publish(const StateMessage& msg) {
  Impl& d = *impl_;
  if (!d.route) return;
  to_idl(msg, d.out_sample);
  if (d.route->write(d.out_sample).value_or(false)) {
    std::lock_guard<std::mutex> lock(d.mu);
    ++d.gate.counters().published;
  }
}

void DdsStateBus::set_interest(const Interest& interest) {
  if (impl_->route)
    impl_->route->set_interest(interest);  // the supervisor hears everyone's records
}

void DdsStateBus::record(const StateMessage& msg) {
  Impl& d = *impl_;
  if (!d.record_writer.writer) return;
  to_idl(msg, d.out_sample);
  if (d.record_writer.writer->write(&d.out_sample) && d.record_writer.listener->matched > 0)
    d.record_writer.listener->written_since_match = true;
}

int DdsStateBus::record_readers_matched() const {
  return impl_->record_writer.listener ? impl_->record_writer.listener->matched.load() : 0;
}

bool DdsStateBus::recorder_confirmed() const {
  Impl& d = *impl_;
  if (!d.record_writer.writer) return false;
  auto& l = *d.record_writer.listener;
  if (l.matched == 0 || !l.written_since_match) return false;
  // Every matched reliable reader acknowledged every sample still in the history (zero wait).
  if (!l.acknowledged && d.record_writer.writer->wait_for_acknowledgments(
                             eprosima::fastrtps::Duration_t(0, 0)) == ReturnCode_t::RETCODE_OK)
    l.acknowledged = true;
  return l.acknowledged;
}

void DdsStateBus::for_each_latest(AgentId self,
                                  const std::function<void(const StateMessage&)>& visit) {
  std::lock_guard<std::mutex> lock(impl_->mu);
  impl_->gate.for_each_latest(self, visit);
}

void DdsStateBus::set_listener(Listener listener) {
  std::lock_guard<std::mutex> lock(impl_->listener_mu);
  impl_->listener = std::move(listener);
}

BusCounters DdsStateBus::counters() const {
  BusCounters c;
  {
    std::lock_guard<std::mutex> lock(impl_->mu);
    c = impl_->gate.counters();
  }
  const StrangerTally& t = impl_->roster_factory.tally;
  std::lock_guard<std::mutex> lock(t.mu);
  c.dropped += t.samples;
  return c;
}

std::set<AgentId> DdsStateBus::strangers() const {
  const StrangerTally& t = impl_->roster_factory.tally;
  std::lock_guard<std::mutex> lock(t.mu);
  return t.ids;
}

const std::string& DdsStateBus::multicast_group() const { return impl_->multicast_group; }

std::uint64_t DdsStateBus::judged_on_arrival() const {
  return impl_->roster_factory.judged_on_arrival.load(std::memory_order_relaxed);
}

std::map<AgentId, std::uint8_t> DdsStateBus::suspects() const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  return impl_->gate.suspects();
}

std::set<std::uint64_t> DdsStateBus::foreign_runs() const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  return impl_->gate.foreign_runs();
}

int DdsStateBus::region_readers_matched(const std::string& region) const {
  return impl_->route ? impl_->route->region_readers_matched(region) : 0;
}

int DdsStateBus::matched_readers() const {
  return impl_->route ? impl_->route->matched_readers() : 0;
}

}  // namespace qswarm
