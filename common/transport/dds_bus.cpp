#include "common/transport/dds_bus.hpp"

#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/shared_mem/SharedMemTransportDescriptor.h>
#include <fastdds/rtps/transport/test_UDPv4TransportDescriptor.h>
#include <spdlog/spdlog.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/DataWriterListener.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include <chrono>
#include <stdexcept>

#include "swarm_statePubSubTypes.h"

namespace qswarm {

namespace dds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastdds::rtps;

std::int64_t wall_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

namespace {

Vec3 vec(const std::array<double, 3>& a) { return Vec3(a[0], a[1], a[2]); }
std::array<double, 3> arr(const Vec3& v) { return {v.x(), v.y(), v.z()}; }

void to_idl(const StateMessage& m, qswarm_msgs::AgentState& s) {
  s.id(m.view.id);
  s.seq(m.seq);
  s.view_seq(m.view.seq);
  s.stamp_s(m.stamp_s);
  s.wall_ns(m.wall_ns);
  s.incarnation(m.incarnation);
  s.mode(static_cast<uint8_t>(m.mode));
  s.phase(m.phase);
  s.consensus(arr(m.view.q));
  s.initial(arr(m.view.q0));
  s.total_weight(m.view.total_weight);
  s.position(arr(m.p_W));
  s.velocity(arr(m.v_W));
  s.orientation({m.q_WB.w(), m.q_WB.x(), m.q_WB.y(), m.q_WB.z()});
  s.rotors({m.rotors_radps[0], m.rotors_radps[1], m.rotors_radps[2], m.rotors_radps[3]});
  s.received(m.received);
  s.dropped(m.dropped);
  s.overruns(m.overruns);
  s.fault_loss(m.fault_loss);
  s.fault_burst(m.fault_burst);
  s.fault_cut(m.fault_cut);
  s.fault_partition(m.fault_partition);
  s.fault_delayed(m.fault_delayed);
  const auto put_links = [](const std::vector<std::pair<AgentId, double>>& in,
                            std::vector<qswarm_msgs::LinkEntry>& out) {
    out.clear();
    for (const auto& [peer, w] : in) {
      if (out.size() >= 256) break;
      qswarm_msgs::LinkEntry e;
      e.peer(peer);
      e.weight(w);
      out.push_back(e);
    }
  };
  put_links(m.links, s.links());
  put_links(m.initial_links, s.initial_links());
  s.flows().clear();
  for (const FlowEntry& f : m.view.flows) {
    if (s.flows().size() >= 256) break;
    qswarm_msgs::FlowEntry e;
    e.peer(f.peer);
    e.flow(arr(f.flow));
    e.weight(f.weight);
    e.active(f.active);
    s.flows().push_back(e);
  }
  s.copies().clear();
  for (const FlowEntry& f : m.view.copies) {
    if (s.copies().size() >= 256) break;
    qswarm_msgs::FlowEntry e;
    e.peer(f.peer);
    e.flow(arr(f.flow));
    s.copies().push_back(e);
  }
}

StateMessage from_idl(const qswarm_msgs::AgentState& s) {
  StateMessage m;
  m.view.id = s.id();
  m.seq = s.seq();
  m.view.seq = s.view_seq();
  m.stamp_s = s.stamp_s();
  m.wall_ns = s.wall_ns();
  m.incarnation = s.incarnation();
  m.mode = static_cast<AgentMode>(s.mode());
  m.phase = s.phase();
  m.view.q = vec(s.consensus());
  m.view.q0 = vec(s.initial());
  m.view.total_weight = s.total_weight();
  m.p_W = vec(s.position());
  m.v_W = vec(s.velocity());
  m.q_WB = Eigen::Quaterniond(s.orientation()[0], s.orientation()[1], s.orientation()[2],
                              s.orientation()[3]);
  m.rotors_radps = RotorSpeeds(s.rotors()[0], s.rotors()[1], s.rotors()[2], s.rotors()[3]);
  m.received = s.received();
  m.dropped = s.dropped();
  m.overruns = s.overruns();
  m.fault_loss = s.fault_loss();
  m.fault_burst = s.fault_burst();
  m.fault_cut = s.fault_cut();
  m.fault_partition = s.fault_partition();
  m.fault_delayed = s.fault_delayed();
  for (const auto& e : s.links()) m.links.emplace_back(e.peer(), e.weight());
  for (const auto& e : s.initial_links()) m.initial_links.emplace_back(e.peer(), e.weight());
  for (const auto& e : s.copies()) m.view.copies.push_back({e.peer(), vec(e.flow()), 0.0, false});
  for (const auto& e : s.flows())
    m.view.flows.push_back({e.peer(), vec(e.flow()), e.weight(), e.active()});
  return m;
}

}  // namespace

struct DdsBus::Impl : public dds::DataReaderListener {
  DdsOptions opts;
  dds::DomainParticipant* participant = nullptr;
  dds::Publisher* publisher = nullptr;
  dds::Subscriber* subscriber = nullptr;
  dds::Topic* topic = nullptr;
  dds::DataWriter* writer = nullptr;
  dds::DataReader* reader = nullptr;
  dds::TypeSupport type{new qswarm_msgs::AgentStatePubSubType()};

  mutable std::mutex mu;
  std::map<AgentId, StateMessage> latest;
  std::set<AgentId> warned;
  BusCounters counters;
  SampleCallback callback;
  struct WriterListener : public dds::DataWriterListener {
    std::atomic<int> matched{0};
    void on_publication_matched(dds::DataWriter*,
                                const dds::PublicationMatchedStatus& st) override {
      matched = st.current_count;
    }
  } writer_listener;
  qswarm_msgs::AgentState out_sample;  // reused: publishing allocates nothing in steady state

  void on_data_available(dds::DataReader* r) override {
    try {
      qswarm_msgs::AgentState s;
      dds::SampleInfo info;
      while (r->take_next_sample(&s, &info) == ReturnCode_t::RETCODE_OK) {
        if (!info.valid_data) continue;
        accept(from_idl(s));
      }
    } catch (const std::exception& e) {
      spdlog::error("dds: listener caught: {}", e.what());
    } catch (...) {
      spdlog::error("dds: listener caught an unknown exception");
    }
  }

  void accept(const StateMessage& m) {
    const std::int64_t now = wall_now_ns();
    const std::string why = check_message(m);  // pure: outside the lock the agent's tick takes
    SampleCallback cb;
    {
      std::lock_guard<std::mutex> lock(mu);
      if (!why.empty()) {
        ++counters.dropped;
        if (warned.insert(m.view.id).second) {
          spdlog::warn(
              "dropped a sample from agent {}: {} (further drops from it are counted, not logged)",
              m.view.id, why);
        }
        return;
      }
      auto it = latest.find(m.view.id);
      if (it != latest.end() && !is_newer(m, it->second)) {
        ++counters.stale;
        return;
      }
      latest[m.view.id] = m;
      ++counters.received;
      cb = callback;
    }
    if (cb) cb(m, now);
  }
};

DdsBus::DdsBus(const DdsOptions& opts) : impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  d.opts = opts;
  dds::DomainParticipantQos pqos;
  pqos.name(opts.participant_name);
  pqos.transport().use_builtin_transports = false;
  if (opts.test_drop_data_percent > 0) {
    auto t = std::make_shared<rtps::test_UDPv4TransportDescriptor>();
    t->interfaceWhiteList.push_back(opts.interface);
    t->dropDataMessagesPercentage = opts.test_drop_data_percent;
    pqos.transport().user_transports.push_back(t);
  } else {
    auto udp = std::make_shared<rtps::UDPv4TransportDescriptor>();
    udp->interfaceWhiteList.push_back(opts.interface);
    pqos.transport().user_transports.push_back(udp);
  }
  if (opts.shared_memory) {
    pqos.transport().user_transports.push_back(
        std::make_shared<rtps::SharedMemTransportDescriptor>());
  }
  // Many participants on one host: allow more port retries than the default 100.
  pqos.wire_protocol().builtin.mutation_tries = 400;
  d.participant =
      dds::DomainParticipantFactory::get_instance()->create_participant(opts.domain_id, pqos);
  if (!d.participant)
    throw std::runtime_error("dds: cannot create a participant on domain " +
                             std::to_string(opts.domain_id));
  d.type.register_type(d.participant);
  d.topic = d.participant->create_topic("qswarm/agent_state", d.type.get_type_name(),
                                        dds::TOPIC_QOS_DEFAULT);
  if (!d.topic) throw std::runtime_error("dds: cannot create the state topic");

  if (opts.publish) {
    d.publisher = d.participant->create_publisher(dds::PUBLISHER_QOS_DEFAULT);
    dds::DataWriterQos wq = dds::DATAWRITER_QOS_DEFAULT;
    wq.reliability().kind = dds::BEST_EFFORT_RELIABILITY_QOS;
    wq.durability().kind = dds::VOLATILE_DURABILITY_QOS;
    wq.history().kind = dds::KEEP_LAST_HISTORY_QOS;
    wq.history().depth = 1;
    wq.data_sharing().off();
    wq.endpoint().history_memory_policy =
        eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
    d.writer = d.publisher->create_datawriter(d.topic, wq, &d.writer_listener);
    if (!d.writer) throw std::runtime_error("dds: cannot create the state writer");
  }

  d.subscriber = d.participant->create_subscriber(dds::SUBSCRIBER_QOS_DEFAULT);
  dds::DataReaderQos rq = dds::DATAREADER_QOS_DEFAULT;
  rq.reliability().kind = dds::BEST_EFFORT_RELIABILITY_QOS;
  rq.durability().kind = dds::VOLATILE_DURABILITY_QOS;
  rq.history().kind = dds::KEEP_LAST_HISTORY_QOS;
  rq.history().depth = 1;
  rq.data_sharing().off();
  rq.resource_limits().max_instances = opts.max_agents + 16;
  rq.resource_limits().max_samples_per_instance = 1;
  rq.resource_limits().max_samples = opts.max_agents + 16;
  rq.resource_limits().allocated_samples = 32;
  rq.endpoint().history_memory_policy =
      eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  d.reader = d.subscriber->create_datareader(d.topic, rq, &d);
  if (!d.reader) throw std::runtime_error("dds: cannot create the state reader");
}

DdsBus::~DdsBus() {
  Impl& d = *impl_;
  if (d.participant) {
    d.participant->delete_contained_entities();
    dds::DomainParticipantFactory::get_instance()->delete_participant(d.participant);
  }
}

void DdsBus::publish(const StateMessage& msg) {
  Impl& d = *impl_;
  if (!d.writer) return;
  to_idl(msg, d.out_sample);
  if (d.writer->write(&d.out_sample)) {
    std::lock_guard<std::mutex> lock(d.mu);
    ++d.counters.published;
  }
}

std::vector<StateMessage> DdsBus::latest(AgentId self) {
  std::lock_guard<std::mutex> lock(impl_->mu);
  std::vector<StateMessage> out;
  out.reserve(impl_->latest.size());
  for (const auto& [id, m] : impl_->latest)
    if (id != self) out.push_back(m);
  return out;
}

void DdsBus::set_sample_callback(SampleCallback cb) {
  std::lock_guard<std::mutex> lock(impl_->mu);
  impl_->callback = std::move(cb);
}

BusCounters DdsBus::counters() const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  return impl_->counters;
}

int DdsBus::matched_readers() const { return impl_->writer_listener.matched; }

}  // namespace qswarm
