#include "common/dds/claim_bus.hpp"

#include <spdlog/spdlog.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include <stdexcept>

#include "common/dds/idl_convert.hpp"
#include "common/dds/qos.hpp"
#include "common/transport/dds_names.hpp"

#include "swarm_statePubSubTypes.h"

namespace qswarm {

namespace dds = eprosima::fastdds::dds;

struct DdsClaimBus::Impl : public dds::DataReaderListener {
  Impl(std::uint64_t run_id, std::size_t capacity_)
      : capacity(capacity_), inbox(run_id, capacity_) {}
  std::size_t capacity;
  ClaimInbox inbox;
  dds::DomainParticipant* participant = nullptr;
  dds::TypeSupport type{new qswarm_msgs::IdClaimPubSubType()};
  dds::Topic* topic = nullptr;
  dds::Publisher* publisher = nullptr;
  dds::Subscriber* subscriber = nullptr;
  dds::DataWriter* writer = nullptr;
  dds::DataReader* reader = nullptr;

  void on_data_available(dds::DataReader* r) override {
    qswarm_msgs::IdClaim s;
    dds::SampleInfo info;
    while (r->take_next_sample(&s, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      if (inbox.hear(from_idl(s)))
        spdlog::warn(
            "id claims: more than {} replicas heard; the one heard longest ago is forgotten for "
            "each new one (further evictions are counted, not logged)",
            capacity);
    }
  }
};

DdsClaimBus::DdsClaimBus(DdsParticipant& participant, std::uint64_t run_id, std::size_t capacity)
    : impl_(std::make_unique<Impl>(run_id, capacity)) {
  Impl& d = *impl_;
  d.participant = participant.get();
  d.type.register_type(d.participant);
  d.topic = d.participant->create_topic(dds_names::kClaimTopic, d.type.get_type_name(),
                                        dds::TOPIC_QOS_DEFAULT);
  if (!d.topic) throw std::runtime_error("dds: cannot create the id-claim topic");
  // Claims carry the run id; the partition keeps another run's claims off the wire as well.
  dds::PublisherQos pub_qos = dds::PUBLISHER_QOS_DEFAULT;
  pub_qos.partition().push_back(dds_names::run_partition(run_id).c_str());
  dds::SubscriberQos sub_qos = dds::SUBSCRIBER_QOS_DEFAULT;
  sub_qos.partition().push_back(dds_names::run_partition(run_id).c_str());
  d.publisher = d.participant->create_publisher(pub_qos);
  d.subscriber = d.participant->create_subscriber(sub_qos);
  if (!d.publisher || !d.subscriber)
    throw std::runtime_error("dds: cannot create the id-claim endpoints");
  // Claims repeat a few times a second: best-effort, the newest replacing the oldest.
  d.writer = d.publisher->create_datawriter(d.topic, best_effort_writer_qos());
  // One instance (the topic has no key): a queue of the latest claims of every writer, taken as
  // they arrive; the newest replace the oldest when a burst overflows it.
  dds::DataReaderQos rq = best_effort_reader_qos(static_cast<int>(capacity));
  rq.resource_limits().max_instances = 1;
  rq.resource_limits().max_samples_per_instance = static_cast<std::int32_t>(capacity);
  rq.resource_limits().max_samples = static_cast<std::int32_t>(capacity);
  d.reader = d.subscriber->create_datareader(d.topic, rq, &d);
  if (!d.writer || !d.reader) throw std::runtime_error("dds: cannot create the id-claim endpoints");
}

DdsClaimBus::~DdsClaimBus() {
  Impl& d = *impl_;
  if (d.reader) {
    d.reader->set_listener(nullptr);
    d.subscriber->delete_datareader(d.reader);
  }
  if (d.writer) d.publisher->delete_datawriter(d.writer);
  if (d.subscriber) d.participant->delete_subscriber(d.subscriber);
  if (d.publisher) d.participant->delete_publisher(d.publisher);
  if (d.topic) d.participant->delete_topic(d.topic);
}

void DdsClaimBus::publish_claim(const IdClaim& claim) {
  qswarm_msgs::IdClaim s;
  to_idl(claim, s);
  impl_->writer->write(&s);
}

std::vector<IdClaim> DdsClaimBus::claims() const { return impl_->inbox.claims(); }

int DdsClaimBus::claim_writers_matched() const {
  dds::SubscriptionMatchedStatus st;
  impl_->reader->get_subscription_matched_status(st);
  return st.current_count;
}

}  // namespace qswarm
