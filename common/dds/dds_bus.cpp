#include "common/dds/dds_bus.hpp"

#include <arpa/inet.h>
#include <fastdds/rtps/attributes/ServerAttributes.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/shared_mem/SharedMemTransportDescriptor.h>
#include <fastdds/rtps/transport/test_UDPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>
#include <netdb.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/DataWriterListener.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/ContentFilteredTopic.hpp>
#include <fastdds/dds/topic/IContentFilter.hpp>
#include <fastdds/dds/topic/IContentFilterFactory.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <stdexcept>
#include <thread>

#include "common/dds/idl_convert.hpp"
#include "common/transport/sample_gate.hpp"

#include "swarm_statePubSubTypes.h"

namespace qswarm {

namespace dds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastdds::rtps;

namespace {

// What a bus's roster filter turned away: the first ids and every sample.
struct StrangerTally {
  static constexpr std::size_t kMaxIds = 64;
  std::mutex mu;
  std::set<AgentId> ids;
  std::uint64_t samples = 0;
};

// The roster filter (DdsOptions::roster): reads the key, the agent id, straight from the serialized
// sample (CDR: a 4-byte encapsulation header, then the id as the first field) instead of Fast
// DDS's SQL filter, which needs the type's description and decodes every sample in full (a 32-agent
// swarm fell behind real time with it).
class RosterFilter final : public dds::IContentFilter {
 public:
  RosterFilter(std::vector<std::pair<AgentId, AgentId>> ranges, StrangerTally& tally)
      : ranges_(std::move(ranges)), tally_(tally) {}
  bool evaluate(const SerializedPayload& payload, const FilterSampleInfo&,
                const GUID_t&) const override {
    if (payload.data == nullptr || payload.length < 8) return false;
    const unsigned char* d = payload.data;
    const bool little = (d[1] & 1) != 0;  // CDR_LE / PL_CDR_LE
    const AgentId id =
        little ? AgentId{d[4]} | AgentId{d[5]} << 8 | AgentId{d[6]} << 16 | AgentId{d[7]} << 24
               : AgentId{d[7]} | AgentId{d[6]} << 8 | AgentId{d[5]} << 16 | AgentId{d[4]} << 24;
    for (const auto& [lo, hi] : ranges_)
      if (id >= lo && id <= hi) return true;
    std::lock_guard<std::mutex> lock(tally_.mu);
    ++tally_.samples;
    if (tally_.ids.size() < StrangerTally::kMaxIds) tally_.ids.insert(id);
    return false;
  }

 private:
  std::vector<std::pair<AgentId, AgentId>> ranges_;
  StrangerTally& tally_;
};

constexpr const char* kRosterFilterClass = "QSWARM_ROSTER";

// One per bus, registered on the bus's own participant (writers do not filter, so it only ever
// makes the filter of this bus's reader), counting into the bus's tally.
class RosterFilterFactory final : public dds::IContentFilterFactory {
 public:
  StrangerTally tally;
  ReturnCode_t create_content_filter(const char*, const char*, const dds::TopicDataType*,
                                     const char* expression, const ParameterSeq&,
                                     dds::IContentFilter*& filter) override {
    auto ranges = parse_roster_filter(expression ? expression : "");
    if (!ranges) return ReturnCode_t::RETCODE_BAD_PARAMETER;
    delete static_cast<RosterFilter*>(filter);  // an expression update replaces the previous one
    filter = new RosterFilter(std::move(*ranges), tally);
    return ReturnCode_t::RETCODE_OK;
  }
  ReturnCode_t delete_content_filter(const char*, dds::IContentFilter* filter) override {
    delete static_cast<RosterFilter*>(filter);  // this factory makes no other kind
    return ReturnCode_t::RETCODE_OK;
  }
};

}  // namespace

struct DdsBus::Impl : public dds::DataReaderListener {
  DdsOptions opts;
  const Clock* clock = nullptr;  // the receiver's wall time, for the gate
  dds::DomainParticipant* participant = nullptr;
  dds::Publisher* publisher = nullptr;
  dds::Subscriber* subscriber = nullptr;
  dds::Topic* topic = nullptr;
  dds::ContentFilteredTopic* roster_topic = nullptr;  // DdsOptions::roster
  RosterFilterFactory roster_factory;                 // outlives the participant (deleted first)
  dds::DataWriter* writer = nullptr;
  dds::DataReader* reader = nullptr;
  dds::TypeSupport type{new qswarm_msgs::AgentStatePubSubType()};

  mutable std::mutex mu;  // the gate
  SampleGate gate;
  // Held while the listener runs and while it is replaced: once set_listener returns, the old
  // listener is neither running nor called again (the agent's decorator unregisters this way
  // before it is destroyed, while DDS threads still deliver).
  std::mutex listener_mu;
  Listener listener;
  struct WriterListener : public dds::DataWriterListener {
    std::atomic<int> matched{0};
    void on_publication_matched(dds::DataWriter*,
                                const dds::PublicationMatchedStatus& st) override {
      matched = st.current_count;
    }
  } writer_listener;
  qswarm_msgs::AgentState out_sample;  // reused: publishing allocates nothing in steady state

  // The id-claim topic (DdsOptions::id_claims), with its own listener.
  dds::TypeSupport claim_type{new qswarm_msgs::IdClaimPubSubType()};
  dds::Topic* claim_topic = nullptr;
  dds::DataWriter* claim_writer = nullptr;
  dds::DataReader* claim_reader = nullptr;
  // The topic has no key, so DDS keeps no state per nonce either: the inbox bounds what is kept.
  std::optional<ClaimInbox> claims;
  void hear_claim(const qswarm_msgs::IdClaim& s) {
    if (claims->hear(from_idl(s)))
      spdlog::warn(
          "id claims: more than {} replicas heard; the one heard longest ago is forgotten for "
          "each new one (further evictions are counted, not logged)",
          claim_capacity(static_cast<std::size_t>(opts.max_agents)));
  }
  struct ClaimListener : public dds::DataReaderListener {
    Impl* d = nullptr;
    void on_data_available(dds::DataReader* r) override {
      qswarm_msgs::IdClaim s;
      dds::SampleInfo info;
      while (r->take_next_sample(&s, &info) == ReturnCode_t::RETCODE_OK) {
        if (info.valid_data) d->hear_claim(s);
      }
    }
  } claim_listener;

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
    const std::string why = check_message(m);  // pure: outside the lock the agent's tick takes
    SampleGate::Result r;
    {
      std::lock_guard<std::mutex> lock(mu);
      r = gate.admit(m, why, clock->wall_ns());
    }
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

DdsBus::DdsBus(const DdsOptions& opts, const Clock& clock) : impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  d.opts = opts;
  d.clock = &clock;
  d.gate = SampleGate(opts.run_id);
  dds::DomainParticipantQos pqos;
  pqos.name(opts.participant_name);
  pqos.transport().use_builtin_transports = false;
  if (opts.test_drop_data_percent > 0) {
    auto t = std::make_shared<rtps::test_UDPv4TransportDescriptor>();
    if (!opts.interface.empty()) t->interfaceWhiteList.push_back(opts.interface);
    t->dropDataMessagesPercentage = opts.test_drop_data_percent;
    pqos.transport().user_transports.push_back(t);
  } else {
    auto udp = std::make_shared<rtps::UDPv4TransportDescriptor>();
    if (!opts.interface.empty()) udp->interfaceWhiteList.push_back(opts.interface);
    pqos.transport().user_transports.push_back(udp);
  }
  if (opts.shared_memory) {
    pqos.transport().user_transports.push_back(
        std::make_shared<rtps::SharedMemTransportDescriptor>());
  }
  // Many participants on one host: allow more port retries than the default 100.
  pqos.wire_protocol().builtin.mutation_tries = 400;
  // Participants announce an infinite lease, so no peer ever runs a lease check on them. Fast DDS
  // 2.9.1 races a peer's lease check (timer thread) against that peer's removal when it leaves
  // (receive thread): the check wakes on a cleared proxy and PDP.cpp:1140 asserts, and Debian's
  // build keeps asserts, so a participant that stays aborted (seen at 64-agent teardowns). The
  // agents judge liveness themselves (the neighbour timeout); a participant that leaves is still
  // removed at once by its DISPOSE, and one that crashes stays a silent proxy until the process
  // ends. Announcements every second, not every 3 s: after the first five, a participant whose
  // announcement was lost (a full UDP receive buffer while many processes start) is heard a
  // period later; the supervisor missed an agent's first 2.7 s that way.
  auto& discovery = pqos.wire_protocol().builtin.discovery_config;
  discovery.leaseDuration = eprosima::fastrtps::c_TimeInfinite;
  discovery.leaseDuration_announcementperiod = eprosima::fastrtps::Duration_t(1, 0);
  if (!opts.discovery_server.empty()) {
    const auto [ip, port] = resolve_discovery_server(opts.discovery_server);
    discovery.discoveryProtocol = eprosima::fastrtps::rtps::DiscoveryProtocol_t::CLIENT;
    rtps::RemoteServerAttributes server;
    rtps::get_server_client_default_guidPrefix(0, server.guidPrefix);
    eprosima::fastrtps::rtps::Locator_t loc;
    eprosima::fastrtps::rtps::IPLocator::setIPv4(loc, ip);
    loc.port = port;
    server.metatrafficUnicastLocatorList.push_back(loc);
    discovery.m_DiscoveryServers.push_back(server);
  }
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
    dds::PublisherQos pub_qos = dds::PUBLISHER_QOS_DEFAULT;
    pub_qos.partition().push_back(run_partition(opts.run_id).c_str());
    d.publisher = d.participant->create_publisher(pub_qos);
    dds::DataWriterQos wq = dds::DATAWRITER_QOS_DEFAULT;
    wq.reliability().kind = dds::BEST_EFFORT_RELIABILITY_QOS;
    wq.durability().kind = dds::VOLATILE_DURABILITY_QOS;
    wq.history().kind = dds::KEEP_LAST_HISTORY_QOS;
    wq.history().depth = 1;
    wq.data_sharing().off();
    // No filtering on the writer's side: it would evaluate each sample for every filtering reader
    // and send per reader (64 agents on 2 cores fell behind with it); the readers filter.
    wq.writer_resource_limits().reader_filters_allocation =
        eprosima::fastrtps::ResourceLimitedContainerConfig(0, 0, 0);
    wq.endpoint().history_memory_policy =
        eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
    d.writer = d.publisher->create_datawriter(d.topic, wq, &d.writer_listener);
    if (!d.writer) throw std::runtime_error("dds: cannot create the state writer");
  }

  dds::SubscriberQos sub_qos = dds::SUBSCRIBER_QOS_DEFAULT;
  sub_qos.partition().push_back(opts.hear_all_runs ? "qswarm-run-*"
                                                   : run_partition(opts.run_id).c_str());
  d.subscriber = d.participant->create_subscriber(sub_qos);
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
  dds::TopicDescription* read_from = d.topic;
  if (!opts.roster.empty()) {
    d.participant->register_content_filter_factory(kRosterFilterClass, &d.roster_factory);
    d.roster_topic = d.participant->create_contentfilteredtopic(
        "qswarm/agent_state/roster", d.topic, roster_filter(opts.roster), {}, kRosterFilterClass);
    if (!d.roster_topic) throw std::runtime_error("dds: cannot create the roster filter");
    read_from = d.roster_topic;
  }
  d.reader = d.subscriber->create_datareader(read_from, rq, &d);
  if (!d.reader) throw std::runtime_error("dds: cannot create the state reader");

  if (opts.id_claims) {
    if (!d.publisher) throw std::runtime_error("dds: id claims need a publishing participant");
    d.claim_type.register_type(d.participant);
    d.claim_topic = d.participant->create_topic("qswarm/id_claim", d.claim_type.get_type_name(),
                                                dds::TOPIC_QOS_DEFAULT);
    if (!d.claim_topic) throw std::runtime_error("dds: cannot create the id-claim topic");
    dds::DataWriterQos cw = dds::DATAWRITER_QOS_DEFAULT;
    cw.reliability().kind = dds::BEST_EFFORT_RELIABILITY_QOS;  // claims repeat a few times a second
    cw.durability().kind = dds::VOLATILE_DURABILITY_QOS;
    cw.history().depth = 1;
    cw.data_sharing().off();
    d.claim_writer = d.publisher->create_datawriter(d.claim_topic, cw);
    dds::DataReaderQos cr = dds::DATAREADER_QOS_DEFAULT;
    cr.reliability().kind = dds::BEST_EFFORT_RELIABILITY_QOS;
    cr.durability().kind = dds::VOLATILE_DURABILITY_QOS;
    cr.data_sharing().off();
    // One instance (the topic has no key): a queue of the latest claims of every writer, taken as
    // they arrive; the newest replace the oldest when a burst overflows it.
    const std::size_t capacity = claim_capacity(static_cast<std::size_t>(opts.max_agents));
    d.claims.emplace(opts.run_id, capacity);
    cr.history().depth = static_cast<std::int32_t>(capacity);
    cr.resource_limits().max_instances = 1;
    cr.resource_limits().max_samples_per_instance = static_cast<std::int32_t>(capacity);
    cr.resource_limits().max_samples = static_cast<std::int32_t>(capacity);
    d.claim_listener.d = &d;
    d.claim_reader = d.subscriber->create_datareader(d.claim_topic, cr, &d.claim_listener);
    if (!d.claim_writer || !d.claim_reader)
      throw std::runtime_error("dds: cannot create the id-claim endpoints");
  }
}

std::pair<std::string, std::uint16_t> resolve_discovery_server(const std::string& host_port) {
  const auto colon = host_port.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == host_port.size())
    throw std::invalid_argument("discovery server \"" + host_port + "\": expected HOST:PORT");
  const std::string host = host_port.substr(0, colon);
  const std::string port_text = host_port.substr(colon + 1);
  char* end = nullptr;
  const long port = std::strtol(port_text.c_str(), &end, 10);
  if (*end != '\0' || port < 1 || port > 65535)
    throw std::invalid_argument("discovery server \"" + host_port + "\": port must be 1..65535");
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* res = nullptr;
  // A container's name may take a moment to appear in the network's DNS (unknown name, no data,
  // a server failure): retry for ~15 s. A numeric address resolves at once.
  int rc = 0;
  for (int attempt = 0; attempt < 30; ++attempt) {
    rc = getaddrinfo(host.c_str(), nullptr, &hints, &res);
    if (rc != EAI_AGAIN && rc != EAI_NONAME && rc != EAI_FAIL && rc != EAI_NODATA) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
  if (rc != 0 || !res)
    throw std::invalid_argument("discovery server \"" + host_port + "\": cannot resolve " + host +
                                " (" + gai_strerror(rc) + ")");
  char buf[INET_ADDRSTRLEN] = {};
  inet_ntop(AF_INET, &reinterpret_cast<sockaddr_in*>(res->ai_addr)->sin_addr, buf, sizeof buf);
  freeaddrinfo(res);
  return {buf, static_cast<std::uint16_t>(port)};
}

DdsBus::~DdsBus() {
  Impl& d = *impl_;
  set_listener(nullptr);
  if (d.reader) d.reader->set_listener(nullptr);
  if (d.claim_reader) d.claim_reader->set_listener(nullptr);
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
    ++d.gate.counters().published;
  }
}

std::vector<StateMessage> DdsBus::latest(AgentId self) {
  std::lock_guard<std::mutex> lock(impl_->mu);
  return impl_->gate.latest(self);
}

void DdsBus::set_listener(Listener listener) {
  std::lock_guard<std::mutex> lock(impl_->listener_mu);
  impl_->listener = std::move(listener);
}

BusCounters DdsBus::counters() const {
  BusCounters c;
  {
    std::lock_guard<std::mutex> lock(impl_->mu);
    c = impl_->gate.counters();
  }
  StrangerTally& t = impl_->roster_factory.tally;
  std::lock_guard<std::mutex> lock(t.mu);
  c.dropped += t.samples;
  return c;
}

std::set<AgentId> DdsBus::strangers() const {
  StrangerTally& t = impl_->roster_factory.tally;
  std::lock_guard<std::mutex> lock(t.mu);
  return t.ids;
}

std::set<std::uint64_t> DdsBus::foreign_runs() const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  return impl_->gate.foreign_runs();
}

std::string run_partition(std::uint64_t run_id) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "qswarm-run-%016llx", static_cast<unsigned long long>(run_id));
  return buf;
}

std::string roster_filter(std::vector<AgentId> roster) {
  std::sort(roster.begin(), roster.end());
  roster.erase(std::unique(roster.begin(), roster.end()), roster.end());
  std::string expr;
  for (std::size_t i = 0; i < roster.size();) {
    std::size_t j = i;
    while (j + 1 < roster.size() && roster[j + 1] == roster[j] + 1) ++j;
    if (!expr.empty()) expr += ",";
    expr += std::to_string(roster[i]);
    if (j > i) expr += "-" + std::to_string(roster[j]);
    i = j + 1;
  }
  return expr;
}

std::optional<std::vector<std::pair<AgentId, AgentId>>> parse_roster_filter(
    const std::string& expr) {
  std::vector<std::pair<AgentId, AgentId>> ranges;
  std::size_t pos = 0;
  const auto number = [&](AgentId& out) {
    std::size_t end = pos;
    while (end < expr.size() && end - pos < 10 &&
           std::isdigit(static_cast<unsigned char>(expr[end])))
      ++end;
    if (end == pos) return false;
    const unsigned long long v = std::stoull(expr.substr(pos, end - pos));
    if (v > std::numeric_limits<AgentId>::max()) return false;
    out = static_cast<AgentId>(v);
    pos = end;
    return true;
  };
  while (pos < expr.size()) {
    AgentId lo = 0;
    if (!number(lo)) return std::nullopt;
    AgentId hi = lo;
    if (pos < expr.size() && expr[pos] == '-') {
      ++pos;
      if (!number(hi) || hi < lo) return std::nullopt;
    }
    ranges.emplace_back(lo, hi);
    if (pos < expr.size() && expr[pos++] != ',') return std::nullopt;
    if (pos == expr.size() && expr.back() == ',') return std::nullopt;
  }
  if (ranges.empty()) return std::nullopt;
  return ranges;
}

void DdsBus::publish_claim(const IdClaim& claim) {
  Impl& d = *impl_;
  if (!d.claim_writer) return;
  qswarm_msgs::IdClaim s;
  to_idl(claim, s);
  d.claim_writer->write(&s);
}

int DdsBus::claim_writers_matched() const {
  if (!impl_->claim_reader) return 0;
  dds::SubscriptionMatchedStatus st;
  impl_->claim_reader->get_subscription_matched_status(st);
  return st.current_count;
}

std::vector<IdClaim> DdsBus::claims() const {
  return impl_->claims ? impl_->claims->claims() : std::vector<IdClaim>{};
}

int DdsBus::matched_readers() const { return impl_->writer_listener.matched; }

}  // namespace qswarm
