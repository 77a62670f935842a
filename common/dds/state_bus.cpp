#include "common/dds/state_bus.hpp"

#include <fastrtps/utils/IPLocator.h>
#include <spdlog/spdlog.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/DataWriterListener.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/ContentFilteredTopic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <stdexcept>

#include "common/dds/idl_convert.hpp"
#include "common/dds/qos.hpp"
#include "common/dds/roster_filter.hpp"
#include "common/dds/writer_registry.hpp"
#include "common/transport/interest.hpp"
#include "common/transport/port_plan.hpp"
#include "common/transport/sample_gate.hpp"

#include "swarm_statePubSubTypes.h"

namespace qswarm {

namespace dds = eprosima::fastdds::dds;

namespace {
std::string partition(const char* stream, std::uint64_t run_id) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "qswarm-%s-%016llx", stream,
                static_cast<unsigned long long>(run_id));
  return buf;
}

// A state or record writer's settings: no filtering on the writer's side (it would evaluate each
// sample for every filtering reader and send per reader: 64 agents on 2 cores fell behind with
// it; readers filter), and a history that allocates nothing in steady state. It reserves one
// payload (of the type's largest size), not Fast DDS's 100: a writer keeps its agent's last
// sample, and every topic has a pool of its own (an agent writes up to 8 region topics).
dds::DataWriterQos unfiltered(dds::DataWriterQos wq) {
  wq.writer_resource_limits().reader_filters_allocation =
      eprosima::fastrtps::ResourceLimitedContainerConfig(0, 0, 0);
  wq.resource_limits().allocated_samples = 1;
  wq.endpoint().history_memory_policy =
      eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  return wq;
}
}  // namespace

std::string run_partition(std::uint64_t run_id) { return partition("run", run_id); }
std::string record_partition(std::uint64_t run_id) { return partition("record", run_id); }

struct DdsStateBus::Impl : public dds::DataReaderListener {
  StateBusOptions opts;
  std::string multicast_group;   // the group its readers listen on ("" : unicast)
  const Clock* clock = nullptr;  // the receiver's wall time, for the gate
  dds::DomainParticipant* participant = nullptr;
  dds::TypeSupport type{new qswarm_msgs::AgentStatePubSubType()};
  dds::Topic* topic = nullptr;                        // qswarm/agent_state: agent to agent
  dds::Topic* record_topic = nullptr;                 // qswarm/record: agent to supervisor
  RosterFilterFactory roster_factory;                 // outlives the filtered topic
  dds::ContentFilteredTopic* roster_topic = nullptr;  // StateBusOptions::roster
  dds::Publisher* publisher = nullptr;
  dds::Publisher* record_publisher = nullptr;
  dds::Subscriber* subscriber = nullptr;
  dds::DataWriter* writer = nullptr;
  dds::DataWriter* record_writer = nullptr;
  dds::DataReader* reader = nullptr;

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
  struct WriterListener : public dds::DataWriterListener {
    std::atomic<int> matched{0};
    // A sample was written since the last match change: a reader matched before it was written
    // must acknowledge it (a volatile writer owes a new reader nothing it wrote before).
    std::atomic<bool> written_since_match{false};
    // Every reader matched now acknowledged such a sample once (it stays so until a match
    // changes: the writer keeps writing, and what it wrote last may still be on its way).
    std::atomic<bool> acknowledged{false};
    void on_publication_matched(dds::DataWriter*,
                                const dds::PublicationMatchedStatus& st) override {
      written_since_match = false;
      acknowledged = false;
      matched = st.current_count;
    }
  } writer_listener, record_listener;
  qswarm_msgs::AgentState out_sample;  // reused: publishing allocates nothing in steady state

  // StateBusOptions::topic_per_name: the writer and reader of each agent name of the interest,
  // on topics of their own in the run's partition; the other names (cells) are partitions of
  // their region's topic (region_topics) or of the shared topic, in `writer` and `reader`, made
  // when first needed. Touched only by the thread that calls set_interest and publish.
  dds::DataWriterQos state_writer_qos;   // the names' writers
  dds::DataWriterQos shared_writer_qos;  // the shared topic's, filtering for its readers if asked
  dds::DataReaderQos state_reader_qos;
  dds::Publisher* named_publisher = nullptr;
  dds::Subscriber* named_subscriber = nullptr;
  struct NamedWriter {
    dds::DataWriter* writer = nullptr;
    std::unique_ptr<WriterListener> listener;
  };
  struct NamedReader {
    dds::ContentFilteredTopic* filtered = nullptr;  // the roster filter on its topic
    dds::DataReader* reader = nullptr;
  };
  std::map<std::string, dds::Topic*> named_topics;  // agent names', inboxes' and regions' topics
  std::map<std::string, NamedWriter> named_writers;
  std::map<std::string, NamedReader> named_readers;
  // Cells are partitions of their region's topic (region_of_cell). A reader per region the
  // listened cells touch, in `subscriber` (whose partitions are those cells). A writer per region
  // the published cell lies in (active: written, its partition that cell), and one per other
  // region within a cell of it (idle: matched with the readers of those cells, never written), so
  // that a move into another region finds a writer its new readers already matched: a new writer
  // would be heard only once the server had relayed it. Each has a publisher of its own, whose
  // partitions are its cells.
  struct RegionWriter {
    dds::Publisher* publisher = nullptr;
    dds::DataWriter* writer = nullptr;
    std::unique_ptr<WriterListener> listener;
    std::vector<std::string> cells;
    bool active = false;
  };
  std::map<std::string, RegionWriter> region_writers;
  std::map<std::string, NamedReader> region_readers;
  bool interest_told = false;
  std::vector<std::string> place_params;  // the shared or region readers' place filter, as told

  static std::string topic_of(const std::string& name) { return "qswarm/agent_state/" + name; }
  dds::Topic* named_topic(const std::string& name) {
    dds::Topic*& t = named_topics[name];
    if (!t)
      t = participant->create_topic(topic_of(name), type.get_type_name(), dds::TOPIC_QOS_DEFAULT);
    if (!t) throw std::runtime_error("dds: cannot create the topic " + topic_of(name));
    return t;
  }
  // Moves the shared topic's writer into the partitions of these names (and of its agent, `self`;
  // 0: none), and its reader, unless it hears all runs.
  void move_writer(const std::vector<std::string>& names, AgentId self);
  void move_reader(const std::vector<std::string>& names);
  // A reader of `topic` for the state stream, behind the roster filter if there is one (with
  // these place filter parameters).
  dds::DataReader* state_reader(dds::Subscriber* sub, dds::Topic* on,
                                dds::ContentFilteredTopic*& filtered,
                                const std::vector<std::string>& place = {});
  // Tells the state readers where they hear by place, and whom by name (`names`, as partitions
  // or topics).
  void set_place(const Interest& interest, const std::vector<std::string>& names);
  void set_named_interest(const Interest& interest);
  // Deletes the readers of regions none of these listened cells lies in. They share the
  // subscriber with every state reader, and go before its partitions change: a reader updated
  // and then deleted at once would reach a Discovery Server as two changes together
  // (StateBusOptions::region_topics), and it hears nothing of its region's cells meanwhile.
  void drop_region_readers_beyond(const std::vector<std::string>& cells);
  // The region topics' endpoints for these published and listened cells (after set_place and
  // drop_region_readers_beyond).
  void set_regions(const std::vector<std::string>& pub, const std::vector<std::string>& sub);
  // Deletes a reader of a name or region, and its filter.
  void delete_reader(dds::Subscriber* sub, const NamedReader& r);
  // Deletes the name's reader and/or writer, and its topic once neither is left.
  void drop_named(const std::string& name, bool its_reader, bool its_writer);
  void drop_region(const std::string& region, bool its_reader, bool its_writer);
  // Deletes the topic of a name or region once no endpoint uses it.
  void drop_topic_if_unused(const std::string& name);
  // Deletes the shared topic's writer or reader (the interest moved to regions and names).
  void drop_shared_writer();
  void drop_shared_reader();

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
        if (opts.topic_per_name) std::fill(w.bytes.begin() + 12, w.bytes.end(), std::uint8_t{0});
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
  d.gate = SampleGate(opts.run_id);
  d.participant = participant.get();
  d.writers = &participant.writers();
  d.bind = participant.secure();
  std::memcpy(d.own_prefix.data(), d.participant->guid().guidPrefix.value, d.own_prefix.size());
  d.type.register_type(d.participant);
  d.topic = d.participant->create_topic("qswarm/agent_state", d.type.get_type_name(),
                                        dds::TOPIC_QOS_DEFAULT);
  d.record_topic =
      d.participant->create_topic("qswarm/record", d.type.get_type_name(), dds::TOPIC_QOS_DEFAULT);
  if (!d.topic || !d.record_topic) throw std::runtime_error("dds: cannot create the state topics");

  if (opts.publish) {
    const auto writer_in = [&](const std::string& part, dds::Publisher*& pub, dds::Topic* topic,
                               const dds::DataWriterQos& wq, dds::DataWriterListener* listener) {
      // The stream's partition, and this agent's own under it (which binds the writer to it).
      dds::PublisherQos pub_qos = dds::PUBLISHER_QOS_DEFAULT;
      pub_qos.partition().push_back(part.c_str());
      if (opts.self != 0)
        pub_qos.partition().push_back((part + '/' + agent_partition(opts.self)).c_str());
      pub = d.participant->create_publisher(pub_qos);
      dds::DataWriter* w = pub ? pub->create_datawriter(topic, wq, listener) : nullptr;
      if (!w) throw std::runtime_error("dds: cannot create a writer in " + part);
      return w;
    };
    dds::DataWriterQos state_qos = unfiltered(best_effort_writer_qos());
    if (opts.filter_at_writer && !opts.recorder) {
      const auto readers = static_cast<std::size_t>(opts.max_agents) + 16;
      state_qos.writer_resource_limits().reader_filters_allocation =
          eprosima::fastrtps::ResourceLimitedContainerConfig(0, readers, 1);
    }
    if (opts.topic_per_name && !opts.recorder) {
      // The writers come with set_interest: the agent names' in this publisher, in the run's
      // partition; the shared topic's in a publisher of its own, whose partitions move.
      d.state_writer_qos = unfiltered(best_effort_writer_qos());
      d.shared_writer_qos = state_qos;
      dds::PublisherQos pub_qos = dds::PUBLISHER_QOS_DEFAULT;
      pub_qos.partition().push_back(run_partition(opts.run_id).c_str());
      d.named_publisher = d.participant->create_publisher(pub_qos);
      d.publisher = d.participant->create_publisher(pub_qos);
      if (!d.named_publisher || !d.publisher)
        throw std::runtime_error("dds: cannot create the state publishers");
    } else {
      d.writer = writer_in(run_partition(opts.run_id), d.publisher, d.topic, state_qos,
                           &d.writer_listener);
    }
    d.record_writer = writer_in(record_partition(opts.run_id), d.record_publisher, d.record_topic,
                                unfiltered(record_writer_qos()), &d.record_listener);
  }

  dds::SubscriberQos sub_qos = dds::SUBSCRIBER_QOS_DEFAULT;
  const std::string mine =
      opts.recorder ? record_partition(opts.run_id) : run_partition(opts.run_id);
  const std::string any_run = opts.recorder ? "qswarm-record-*" : "qswarm-run-*";
  sub_qos.partition().push_back(opts.hear_all_runs ? any_run.c_str() : mine.c_str());
  d.subscriber = d.participant->create_subscriber(sub_qos);
  if (!d.subscriber) throw std::runtime_error("dds: cannot create the state subscriber");
  dds::DataReaderQos rq = opts.recorder ? record_reader_qos() : best_effort_reader_qos();
  rq.resource_limits().max_instances = opts.max_agents + 16;
  rq.resource_limits().max_samples_per_instance = 1;
  rq.resource_limits().max_samples = opts.max_agents + 16;
  // Reserved at creation, grown when needed: a state reader is one of up to 8 (one per region
  // topic), each with a pool of its own, and its listener takes what arrives at once.
  rq.resource_limits().allocated_samples = opts.recorder ? 32 : 4;
  rq.endpoint().history_memory_policy =
      eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  std::memcpy(d.roster_factory.local.data(), d.own_prefix.data(), d.own_prefix.size());
  // A writer that filters for its readers finds their filter's class here.
  if (!opts.roster.empty() || opts.filter_at_writer)
    d.participant->register_content_filter_factory(RosterFilterFactory::kRosterFilterClass,
                                                   &d.roster_factory);
  if (!opts.recorder && !opts.multicast_group.empty()) {
    namespace rtps = eprosima::fastrtps::rtps;
    rtps::Locator_t group;
    if (participant.options().interface.empty() ||
        !rtps::IPLocator::setIPv4(group, opts.multicast_group) ||
        !rtps::IPLocator::isMulticast(group))
      throw std::invalid_argument("dds: a multicast state reader needs an IPv4 group (not \"" +
                                  opts.multicast_group + "\") and one interface address");
    group.port = PortPlan::data_multicast_port(participant.options().domain_id);
    // Fast DDS only logs a group socket it could not bind, and a reader listening on the group
    // alone would then hear nothing: a program holding the port alone leaves this reader on
    // unicast instead, and says so.
    if (const std::string problem = multicast_port_problem(opts.multicast_group, group.port,
                                                           participant.options().interface);
        !problem.empty()) {
      spdlog::warn("dds: state samples by unicast, not multicast group {}: {}",
                   opts.multicast_group, problem);
    } else {
      // The group alone, no unicast locator: a writer then always sends this reader's samples
      // to the group. With both, a writer sends to a reader's unicast locator once it is the
      // last one left in the group, and Fast DDS 2.9.1 (Debian builds it with statistics and
      // assertions) aborts on a destination it first saw as part of a group (its transport's
      // statistics record a destination only when a match selects it): agents died so at
      // teardown.
      rq.endpoint().multicast_locator_list.push_back(group);
      d.multicast_group = opts.multicast_group;
      spdlog::info("dds: state samples by multicast group {} port {}", d.multicast_group,
                   group.port);
    }
  }
  d.state_reader_qos = rq;
  if (opts.topic_per_name && !opts.recorder) {
    // The readers come with set_interest: the agent names' in this subscriber.
    d.named_subscriber = d.participant->create_subscriber(sub_qos);
    if (!d.named_subscriber) throw std::runtime_error("dds: cannot create the state subscriber");
    return;
  }
  d.reader = d.state_reader(d.subscriber, opts.recorder ? d.record_topic : d.topic, d.roster_topic);
}

dds::DataReader* DdsStateBus::Impl::state_reader(dds::Subscriber* sub, dds::Topic* on,
                                                 dds::ContentFilteredTopic*& filtered,
                                                 const std::vector<std::string>& place) {
  dds::TopicDescription* from = on;
  if (!opts.roster.empty()) {
    // Where it listens is in its parameters only where writers judge it for it (set_place).
    filtered = participant->create_contentfilteredtopic(
        on->get_name() + "/roster", on, roster_filter(opts.roster, opts.self),
        opts.filter_at_writer ? place : std::vector<std::string>{},
        RosterFilterFactory::kRosterFilterClass);
    if (!filtered) throw std::runtime_error("dds: cannot create the roster filter");
    from = filtered;
  }
  dds::DataReader* r = sub->create_datareader(from, state_reader_qos, this);
  if (!r) {
    // Its filter goes too: left behind, its name would refuse the next reader of this topic.
    if (filtered) participant->delete_contentfilteredtopic(filtered);
    filtered = nullptr;
    throw std::runtime_error("dds: cannot create a state reader of " + on->get_name());
  }
  return r;
}

DdsStateBus::~DdsStateBus() {
  Impl& d = *impl_;
  set_listener(nullptr);
  // Deleted here, not left to the participant: the reader's listener is this object, and the
  // filter's factory lives in it.
  d.drop_shared_reader();
  while (!d.region_readers.empty()) d.drop_region(d.region_readers.begin()->first, true, true);
  while (!d.region_writers.empty()) d.drop_region(d.region_writers.begin()->first, true, true);
  while (!d.named_readers.empty()) d.drop_named(d.named_readers.begin()->first, true, true);
  while (!d.named_writers.empty()) d.drop_named(d.named_writers.begin()->first, true, true);
  if (d.named_subscriber) d.participant->delete_subscriber(d.named_subscriber);
  if (d.named_publisher) d.participant->delete_publisher(d.named_publisher);
  if (d.subscriber) d.participant->delete_subscriber(d.subscriber);
  if (d.writer) d.publisher->delete_datawriter(d.writer);
  if (d.publisher) d.participant->delete_publisher(d.publisher);
  if (d.record_writer) d.record_publisher->delete_datawriter(d.record_writer);
  if (d.record_publisher) d.participant->delete_publisher(d.record_publisher);
  if (!d.opts.roster.empty())
    d.participant->unregister_content_filter_factory(RosterFilterFactory::kRosterFilterClass);
  if (d.topic) d.participant->delete_topic(d.topic);
  if (d.record_topic) d.participant->delete_topic(d.record_topic);
}

void DdsStateBus::publish(const StateMessage& msg) {
  Impl& d = *impl_;
  if (d.opts.topic_per_name && !d.interest_told && !d.opts.recorder) set_interest({});
  if (!d.writer && d.named_writers.empty() && d.region_writers.empty()) return;
  to_idl(msg, d.out_sample);
  bool written = !d.writer || d.writer->write(&d.out_sample);
  for (auto& [name, w] : d.named_writers)  // an agent name nobody listens to costs nothing
    if (w.listener->matched > 0) written = w.writer->write(&d.out_sample) && written;
  for (auto& [region, w] : d.region_writers)
    if (w.active && w.listener->matched > 0) written = w.writer->write(&d.out_sample) && written;
  if (written) {
    std::lock_guard<std::mutex> lock(d.mu);
    ++d.gate.counters().published;
  }
}

namespace {
// The DDS partitions of an interest: the run's partition, or one under it per name (a reader's
// cells as patterns: dds_partition_names); and the writer's own agent partition (`self`, 0:
// none), which binds it to its agent.
dds::PartitionQosPolicy partitions(const std::string& run, std::vector<std::string> names,
                                   bool reader, AgentId self = 0) {
  dds::PartitionQosPolicy p;
  if (names.empty()) p.push_back(run.c_str());
  if (self != 0 && std::find(names.begin(), names.end(), agent_partition(self)) == names.end())
    names.push_back(agent_partition(self));
  for (const std::string& n : dds_partition_names(names, reader)) {
    std::string full = run;
    full += '/';
    full += n;
    p.push_back(full.c_str());
  }
  return p;
}
}  // namespace

void DdsStateBus::Impl::move_writer(const std::vector<std::string>& names, AgentId self) {
  if (!publisher) return;
  dds::PublisherQos q = publisher->get_qos();
  const dds::PartitionQosPolicy want =
      partitions(run_partition(opts.run_id), names, /*reader=*/false, self);
  // set_qos updates each of its endpoints through discovery, even with nothing changed.
  if (q.partition().names() == want.names()) return;
  q.partition() = want;
  if (publisher->set_qos(q) != ReturnCode_t::RETCODE_OK)
    throw std::runtime_error("dds: cannot move the state writer's partitions");
}

void DdsStateBus::Impl::move_reader(const std::vector<std::string>& names) {
  if (opts.hear_all_runs) return;
  dds::SubscriberQos q = subscriber->get_qos();
  const dds::PartitionQosPolicy want =
      partitions(run_partition(opts.run_id), names, /*reader=*/true);
  if (q.partition().names() == want.names()) return;  // as move_writer
  q.partition() = want;
  if (subscriber->set_qos(q) != ReturnCode_t::RETCODE_OK)
    throw std::runtime_error("dds: cannot move the state reader's partitions");
}

void DdsStateBus::Impl::delete_reader(dds::Subscriber* sub, const NamedReader& r) {
  r.reader->set_listener(nullptr);
  sub->delete_datareader(r.reader);
  if (r.filtered) participant->delete_contentfilteredtopic(r.filtered);
}

void DdsStateBus::Impl::drop_named(const std::string& name, bool its_reader, bool its_writer) {
  if (auto r = named_readers.find(name); its_reader && r != named_readers.end()) {
    delete_reader(named_subscriber, r->second);
    named_readers.erase(r);
  }
  if (auto w = named_writers.find(name); its_writer && w != named_writers.end()) {
    named_publisher->delete_datawriter(w->second.writer);
    named_writers.erase(w);
  }
  drop_topic_if_unused(name);
}

void DdsStateBus::Impl::drop_topic_if_unused(const std::string& name) {
  if (named_readers.count(name) || named_writers.count(name) || region_readers.count(name) ||
      region_writers.count(name))
    return;
  if (auto t = named_topics.find(name); t != named_topics.end()) {
    participant->delete_topic(t->second);
    named_topics.erase(t);
  }
}

void DdsStateBus::Impl::drop_region(const std::string& region, bool its_reader, bool its_writer) {
  if (auto r = region_readers.find(region); its_reader && r != region_readers.end()) {
    delete_reader(subscriber, r->second);
    region_readers.erase(r);
  }
  if (auto w = region_writers.find(region); its_writer && w != region_writers.end()) {
    w->second.publisher->delete_datawriter(w->second.writer);
    participant->delete_publisher(w->second.publisher);
    region_writers.erase(w);
  }
  drop_topic_if_unused(region);
}

void DdsStateBus::Impl::drop_shared_writer() {
  if (!writer) return;
  publisher->delete_datawriter(writer);
  writer = nullptr;
  writer_listener.matched = 0;
}

void DdsStateBus::Impl::drop_shared_reader() {
  if (!reader) return;
  delete_reader(subscriber, {roster_topic, reader});
  reader = nullptr;
  roster_topic = nullptr;
}

void DdsStateBus::Impl::drop_region_readers_beyond(const std::vector<std::string>& cells) {
  std::set<std::string> regions;
  for (const std::string& c : cells) regions.insert(*region_of_cell(c));
  std::vector<std::string> gone;
  for (const auto& [region, r] : region_readers)
    if (!regions.count(region)) gone.push_back(region);
  for (const std::string& region : gone) drop_region(region, true, false);
}

void DdsStateBus::Impl::set_regions(const std::vector<std::string>& pub,
                                    const std::vector<std::string>& sub) {
  // Readers: those that go are gone (drop_region_readers_beyond); the subscriber's partitions
  // are every listened cell, whatever the region (a writer of one region never publishes
  // another's cells), and the new ones come with them.
  std::set<std::string> regions;
  for (const std::string& c : sub) regions.insert(*region_of_cell(c));
  if (!sub.empty()) move_reader(sub);
  for (const std::string& region : regions) {
    if (region_readers.count(region)) continue;
    NamedReader r;
    r.reader = state_reader(subscriber, named_topic(region), r.filtered, place_params);
    region_readers.emplace(region, r);
  }

  // Writers: the cells each region's writer publishes into, those of the active ones first.
  std::map<std::string, std::pair<std::vector<std::string>, bool>> want;  // region: cells, active
  if (opts.publish) {
    for (const std::string& c : pub) {
      auto& [cells, active] = want[*region_of_cell(c)];
      cells.push_back(c);
      active = true;
    }
    for (const std::string& c : pub)
      for (const std::string& near : cells_about(c, 1)) {
        const std::optional<std::string> region = region_of_cell(near);
        if (!region) continue;  // past the cells' bounds
        auto& [cells, active] = want[*region];
        if (!active) cells.push_back(near);
      }
  }
  for (auto& [region, w] : want) {
    auto& [cells, active] = w;
    std::sort(cells.begin(), cells.end());
    cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
    auto it = region_writers.find(region);
    if (it != region_writers.end()) {
      RegionWriter& rw = it->second;
      rw.active = active;
      if (rw.cells == cells) continue;
      dds::PublisherQos q = rw.publisher->get_qos();
      q.partition() = partitions(run_partition(opts.run_id), cells, /*reader=*/false);
      if (rw.publisher->set_qos(q) != ReturnCode_t::RETCODE_OK)
        throw std::runtime_error("dds: cannot move a state writer's partitions");
      rw.cells = cells;
      continue;
    }
    dds::Topic* on = named_topic(region);
    RegionWriter rw;
    dds::PublisherQos q = dds::PUBLISHER_QOS_DEFAULT;
    q.partition() = partitions(run_partition(opts.run_id), cells, /*reader=*/false);
    rw.publisher = participant->create_publisher(q);
    if (!rw.publisher) throw std::runtime_error("dds: cannot create a state publisher");
    rw.listener = std::make_unique<WriterListener>();
    rw.writer = rw.publisher->create_datawriter(on, shared_writer_qos, rw.listener.get());
    if (!rw.writer) {
      participant->delete_publisher(rw.publisher);
      throw std::runtime_error("dds: cannot create a state writer of " + topic_of(region));
    }
    rw.cells = cells;
    rw.active = active;
    region_writers.emplace(region, std::move(rw));
  }
  std::vector<std::string> gone;
  for (const auto& [region, w] : region_writers)
    if (!want.count(region)) gone.push_back(region);
  for (const std::string& region : gone) drop_region(region, false, true);
}

void DdsStateBus::Impl::set_named_interest(const Interest& interest) {
  interest_told = true;
  // Agent names and inboxes are topics, cells partitions of their region's topic (region_topics);
  // other names partitions of the shared topic, which also carries the whole run (the empty
  // interest).
  const auto named = [](const std::string& n) {
    return agent_of_partition(n).has_value() || inbox_of_partition(n).has_value();
  };
  std::vector<std::string> agents_pub, cells_pub, shared_pub, agents_sub, cells_sub, shared_sub;
  // Regions for the cells of one space only: with two (proximity and collision avoidance) a
  // sample would go out once per space's region, and a listener of both would count it twice.
  std::set<char> spaces;
  for (const auto* names : {&interest.publish, &interest.subscribe})
    for (const std::string& n : *names)
      if (region_of_cell(n)) spaces.insert(n[0]);
  const auto cell = [&](const std::string& n) {
    return opts.region_topics && spaces.size() == 1 && region_of_cell(n).has_value();
  };
  for (const std::string& n : interest.publish)
    (named(n) ? agents_pub : cell(n) ? cells_pub : shared_pub).push_back(n);
  for (const std::string& n : interest.subscribe)
    (named(n) ? agents_sub : cell(n) ? cells_sub : shared_sub).push_back(n);
  // Where it hears by place. Kept in the process (set_place), the place also judges what the
  // names' own topics bring: it names them, so that a sample heard by name passes wherever it
  // is. Told to writers, it need not (the names' readers have no place of their own).
  set_place(interest, opts.filter_at_writer ? std::vector<std::string>{} : agents_sub);
  // The shared topic's endpoints are made once needed, after their partitions are set: they
  // never hear the whole run on the way.
  if (opts.publish && (interest.publish.empty() || !shared_pub.empty())) {
    move_writer(shared_pub, 0);
    if (!writer) writer = publisher->create_datawriter(topic, shared_writer_qos, &writer_listener);
    if (!writer) throw std::runtime_error("dds: cannot create the state writer");
  } else {
    drop_shared_writer();
  }
  const bool shared_reader = interest.subscribe.empty() || !shared_sub.empty();
  if (shared_reader && !cells_sub.empty())  // the subscriber's partitions are the cells'
    throw std::invalid_argument("dds: an interest listens to cells and to names of no cell");
  drop_region_readers_beyond(cells_sub);
  if (shared_reader) {
    move_reader(shared_sub);
    if (!reader) reader = state_reader(subscriber, topic, roster_topic, place_params);
  } else {
    drop_shared_reader();
  }
  set_regions(cells_pub, cells_sub);
  // The agent names: new endpoints first, then the old ones go.
  const auto has = [](const std::vector<std::string>& v, const std::string& n) {
    return std::find(v.begin(), v.end(), n) != v.end();
  };
  for (const std::string& n : agents_sub) {
    if (named_readers.count(n)) continue;
    NamedReader r;
    r.reader = state_reader(named_subscriber, named_topic(n), r.filtered);
    named_readers.emplace(n, r);
  }
  if (opts.publish)
    for (const std::string& n : agents_pub) {
      if (named_writers.count(n)) continue;
      NamedWriter w;
      w.listener = std::make_unique<WriterListener>();
      w.writer =
          named_publisher->create_datawriter(named_topic(n), state_writer_qos, w.listener.get());
      if (!w.writer)
        throw std::runtime_error("dds: cannot create a state writer of " + topic_of(n));
      named_writers.emplace(n, std::move(w));
    }
  std::vector<std::string> gone;
  for (const auto& [n, r] : named_readers)
    if (!has(agents_sub, n)) gone.push_back(n);
  for (const auto& [n, w] : named_writers)
    if (!has(agents_pub, n)) gone.push_back(n);
  for (const std::string& n : gone) drop_named(n, !has(agents_sub, n), !has(agents_pub, n));
}

void DdsStateBus::Impl::set_place(const Interest& interest, const std::vector<std::string>& names) {
  std::vector<AgentId> ids;
  for (const std::string& n : names)
    if (const auto id = agent_of_partition(n)) ids.push_back(*id);
  std::vector<std::string> params = place_filter(interest.near, ids);
  if (params == place_params) return;  // each change travels to every matched peer
  if (!opts.filter_at_writer) {
    // No writer judges for its readers: the place stays in this process, and a move updates
    // each reader through discovery once (its partitions), not twice.
    const std::optional<PlaceFilter> place = parse_place_filter(params);
    if (!place) throw std::runtime_error("dds: cannot set a state reader's place filter");
    roster_factory.set_local_place(*place);
    place_params = std::move(params);
    return;
  }
  // The shared topic's reader and the region readers (no filter without a roster: a test's bus).
  std::vector<dds::ContentFilteredTopic*> filters{roster_topic};
  for (const auto& [region, r] : region_readers) filters.push_back(r.filtered);
  for (dds::ContentFilteredTopic* f : filters)
    if (f && f->set_expression_parameters(params) != ReturnCode_t::RETCODE_OK)
      throw std::runtime_error("dds: cannot set a state reader's place filter");
  place_params = std::move(params);
}

void DdsStateBus::set_interest(const Interest& interest) {
  Impl& d = *impl_;
  if (d.opts.recorder) return;  // the supervisor hears the record stream, everyone's
  if (d.opts.topic_per_name) {
    d.set_named_interest(interest);
    return;
  }
  d.move_writer(interest.publish, d.opts.self);
  // Names and cells are partitions of one topic: a sample heard by name passes whatever its place.
  d.set_place(interest, interest.subscribe);
  d.move_reader(interest.subscribe);
}

void DdsStateBus::record(const StateMessage& msg) {
  Impl& d = *impl_;
  if (!d.record_writer) return;
  to_idl(msg, d.out_sample);
  if (d.record_writer->write(&d.out_sample) && d.record_listener.matched > 0)
    d.record_listener.written_since_match = true;
}

int DdsStateBus::record_readers_matched() const { return impl_->record_listener.matched; }

bool DdsStateBus::recorder_confirmed() const {
  Impl& d = *impl_;
  auto& l = d.record_listener;
  if (!d.record_writer || l.matched == 0 || !l.written_since_match) return false;
  // Every matched reliable reader acknowledged every sample still in the history (zero wait).
  if (!l.acknowledged && d.record_writer->wait_for_acknowledgments(
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
  const auto it = impl_->region_writers.find(region);
  return it == impl_->region_writers.end() ? 0 : it->second.listener->matched.load();
}

int DdsStateBus::matched_readers() const {
  int n = impl_->writer_listener.matched;
  for (const auto& [name, w] : impl_->named_writers) n += w.listener->matched;
  for (const auto& [region, w] : impl_->region_writers)
    if (w.active) n += w.listener->matched;
  return n;
}

}  // namespace qswarm
