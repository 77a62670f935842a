#include "common/dds/state_endpoints.hpp"

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/ContentFilteredTopic.hpp>

#include <algorithm>
#include <stdexcept>

#include "common/dds/qos.hpp"
#include "common/transport/dds_names.hpp"

namespace qswarm::state_bus {

void WriterListener::on_publication_matched(dds::DataWriter*,
                                            const dds::PublicationMatchedStatus& st) {
  written_since_match = false;
  acknowledged = false;
  matched = st.current_count;
}

dds::DataWriterQos unfiltered(dds::DataWriterQos wq) {
  wq.writer_resource_limits().reader_filters_allocation =
      eprosima::fastrtps::ResourceLimitedContainerConfig(0, 0, 0);
  wq.resource_limits().allocated_samples = 1;
  wq.endpoint().history_memory_policy =
      eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  return wq;
}

StateEndpoints::StateEndpoints(dds::DomainParticipant* participant, const StateBusOptions& opts,
                               const std::string& type_name, dds::Topic* shared_topic,
                               dds::DataReaderListener* listener, RosterFilterFactory& roster,
                               dds::DataReaderQos reader_qos)
    : participant_(participant),
      opts_(opts),
      type_name_(type_name),
      shared_topic_(shared_topic),
      listener_(listener),
      roster_(roster),
      reader_qos_(std::move(reader_qos)),
      writer_qos_(unfiltered(best_effort_writer_qos())) {}

dds::Topic* StateEndpoints::acquire_topic(const std::string& name) {
  Counted& c = topics_[name];
  if (!c.topic) {
    c.topic = participant_->create_topic(dds_names::state_topic_of(name), type_name_,
                                         dds::TOPIC_QOS_DEFAULT);
    if (!c.topic) {
      topics_.erase(name);
      throw std::runtime_error("dds: cannot create the topic " + dds_names::state_topic_of(name));
    }
  }
  ++c.users;
  return c.topic;
}

void StateEndpoints::release_topic(const std::string& name) {
  const auto it = topics_.find(name);
  if (it == topics_.end() || --it->second.users > 0) return;
  participant_->delete_topic(it->second.topic);
  topics_.erase(it);
}

std::vector<std::string> StateEndpoints::partitions(std::vector<std::string> names, bool reader,
                                                    AgentId self) const {
  const std::string run = dds_names::run_partition(opts_.run_id);
  std::vector<std::string> out;
  if (names.empty()) out.push_back(run);
  if (self != 0 && std::find(names.begin(), names.end(), agent_partition(self)) == names.end())
    names.push_back(agent_partition(self));
  for (const std::string& n : dds_partition_names(names, reader)) {
    std::string full = run;
    full += '/';
    full += n;
    out.push_back(std::move(full));
  }
  return out;
}

namespace {
dds::PartitionQosPolicy policy(const std::vector<std::string>& names) {
  dds::PartitionQosPolicy p;
  for (const std::string& n : names) p.push_back(n.c_str());
  return p;
}
}  // namespace

Writer StateEndpoints::make_writer(dds::Topic* on, const std::vector<std::string>& names,
                                   AgentId self) {
  Writer w;
  dds::PublisherQos q = dds::PUBLISHER_QOS_DEFAULT;
  q.partition() = policy(partitions(names, /*reader=*/false, self));
  w.publisher = participant_->create_publisher(q);
  if (!w.publisher) throw std::runtime_error("dds: cannot create a state publisher");
  w.listener = std::make_unique<WriterListener>();
  w.writer = w.publisher->create_datawriter(on, writer_qos_, w.listener.get());
  if (!w.writer) {
    participant_->delete_publisher(w.publisher);
    throw std::runtime_error("dds: cannot create a state writer of " + on->get_name());
  }
  w.names = names;
  return w;
}

void StateEndpoints::move_writer(Writer& w, const std::vector<std::string>& names, AgentId self) {
  dds::PublisherQos q = w.publisher->get_qos();
  const dds::PartitionQosPolicy want = policy(partitions(names, /*reader=*/false, self));
  // set_qos updates each of its endpoints through discovery, even with nothing changed.
  if (q.partition().names() == want.names()) return;
  q.partition() = want;
  if (w.publisher->set_qos(q) != ReturnCode_t::RETCODE_OK)
    throw std::runtime_error("dds: cannot move a state writer's partitions");
  w.names = names;
}

void StateEndpoints::delete_writer(Writer& w) {
  if (w.writer) w.publisher->delete_datawriter(w.writer);
  if (w.publisher) participant_->delete_publisher(w.publisher);
  w.writer = nullptr;
  w.publisher = nullptr;
}

dds::Subscriber* StateEndpoints::make_subscriber(const std::vector<std::string>& names) {
  dds::SubscriberQos q = dds::SUBSCRIBER_QOS_DEFAULT;
  q.partition() = opts_.hear_all_runs
                      ? policy({dds_names::any_run_partition(dds_names::kRunStream)})
                      : policy(partitions(names, /*reader=*/true));
  dds::Subscriber* sub = participant_->create_subscriber(q);
  if (!sub) throw std::runtime_error("dds: cannot create the state subscriber");
  return sub;
}

void StateEndpoints::move_subscriber(dds::Subscriber* sub, const std::vector<std::string>& names) {
  if (opts_.hear_all_runs) return;
  dds::SubscriberQos q = sub->get_qos();
  const dds::PartitionQosPolicy want = policy(partitions(names, /*reader=*/true));
  if (q.partition().names() == want.names()) return;  // as move_writer
  q.partition() = want;
  if (sub->set_qos(q) != ReturnCode_t::RETCODE_OK)
    throw std::runtime_error("dds: cannot move the state reader's partitions");
}

Reader StateEndpoints::make_reader(dds::Subscriber* sub, dds::Topic* on) {
  Reader r;
  dds::TopicDescription* from = on;
  if (!opts_.roster.empty()) {
    r.filtered = participant_->create_contentfilteredtopic(
        on->get_name() + "/roster", on, roster_filter(opts_.roster, opts_.self), {},
        RosterFilterFactory::kRosterFilterClass);
    if (!r.filtered) throw std::runtime_error("dds: cannot create the roster filter");
    from = r.filtered;
  }
  r.reader = sub->create_datareader(from, reader_qos_, listener_);
  if (!r.reader) {
    // Its filter goes too: left behind, its name would refuse the next reader of this topic.
    if (r.filtered) participant_->delete_contentfilteredtopic(r.filtered);
    throw std::runtime_error("dds: cannot create a state reader of " + on->get_name());
  }
  return r;
}

void StateEndpoints::delete_reader(dds::Subscriber* sub, Reader& r) {
  if (!r.reader) return;
  r.reader->set_listener(nullptr);
  sub->delete_datareader(r.reader);
  if (r.filtered) participant_->delete_contentfilteredtopic(r.filtered);
  r = Reader{};
}

void StateEndpoints::set_place(const Interest& interest, const std::vector<std::string>& names) {
  PlaceFilter place;
  place.near = interest.near;
  if (!place.near.empty()) {
    std::vector<AgentId> ids;
    for (const std::string& n : names)
      if (const auto id = agent_of_partition(n)) ids.push_back(*id);
    if (const auto heard = parse_roster_filter(roster_filter(ids))) place.names = heard->ranges;
  }
  if (place_told_ && place == place_) return;
  place_ = place;
  place_told_ = true;
  roster_.set_local_place(std::move(place));
}

}  // namespace qswarm::state_bus
