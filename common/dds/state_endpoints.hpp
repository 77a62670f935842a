#pragma once

// Inside the DDS adapter: the state stream's endpoints as every routing makes them (this file), and
// the routings (state_routes.hpp). DdsStateBus owns both; nothing outside common/dds sees them.

#include <atomic>
#include <map>
#include <string>
#include <vector>

#include <fastdds/dds/publisher/DataWriterListener.hpp>
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include "common/dds/roster_filter.hpp"
#include "common/dds/state_bus.hpp"

namespace eprosima::fastdds::dds {
class ContentFilteredTopic;
class DataReader;
class DataReaderListener;
class DataWriter;
class DomainParticipant;
class Publisher;
class Subscriber;
class Topic;
}  // namespace eprosima::fastdds::dds

namespace qswarm::state_bus {

namespace dds = eprosima::fastdds::dds;

// The readers matched with a writer, and whether they acknowledged what it wrote since.
struct WriterListener : public dds::DataWriterListener {
  std::atomic<int> matched{0};
  // A sample was written since the last match change: a reader matched before it was written
  // must acknowledge it (a volatile writer owes a new reader nothing it wrote before).
  std::atomic<bool> written_since_match{false};
  // Every reader matched now acknowledged such a sample once (it stays so until a match changes).
  std::atomic<bool> acknowledged{false};
  void on_publication_matched(dds::DataWriter*, const dds::PublicationMatchedStatus& st) override;
};

// A state reader behind the roster filter (no filter: a test's bus without a roster).
struct Reader {
  dds::ContentFilteredTopic* filtered = nullptr;
  dds::DataReader* reader = nullptr;
};

// A writer of its own publisher, whose partitions are the writer's.
struct Writer {
  dds::Publisher* publisher = nullptr;
  dds::DataWriter* writer = nullptr;
  std::unique_ptr<WriterListener> listener;
  std::vector<std::string> names;  // the interest's names it publishes into
};

// What every routing makes the state stream's endpoints with: the participant, the shared topic,
// the QoS, the roster filter and the bus's listener; topics of names and regions made when first
// needed and deleted with their last endpoint.
class StateEndpoints {
 public:
  StateEndpoints(dds::DomainParticipant* participant, const StateBusOptions& opts,
                 const std::string& type_name, dds::Topic* shared_topic,
                 dds::DataReaderListener* listener, RosterFilterFactory& roster,
                 dds::DataReaderQos reader_qos);
  StateEndpoints(const StateEndpoints&) = delete;
  StateEndpoints& operator=(const StateEndpoints&) = delete;

  const StateBusOptions& opts() const { return opts_; }
  dds::DomainParticipant* participant() const { return participant_; }
  dds::Topic* shared_topic() const { return shared_topic_; }

  // The topic of a name or region ("qswarm/agent_state/a7"): acquired by each endpoint on it.
  dds::Topic* acquire_topic(const std::string& name);
  void release_topic(const std::string& name);
  // An endpoint made on the topic of `name` by `make` (the topic released again if it throws).
  template <typename Make>
  auto on_topic(const std::string& name, Make make) {
    dds::Topic* t = acquire_topic(name);
    try {
      return make(t);
    } catch (...) {
      release_topic(name);
      throw;
    }
  }

  // The DDS partitions of an interest's names: the run's partition when there are none, else one
  // under it per name (a reader's cells as patterns), and the writer's agent partition (`self`,
  // 0: none), which binds it to its agent.
  std::vector<std::string> partitions(std::vector<std::string> names, bool reader,
                                      AgentId self = 0) const;

  // A writer of `on` in a publisher of its own, in these partitions; moved by move_writer.
  Writer make_writer(dds::Topic* on, const std::vector<std::string>& names, AgentId self = 0);
  // Its publisher into other partitions (each change travels to every matched peer: none when
  // they are the same).
  void move_writer(Writer& w, const std::vector<std::string>& names, AgentId self = 0);
  void delete_writer(Writer& w);

  // A subscriber whose partitions are these names' (hear_all_runs: every run's partition).
  dds::Subscriber* make_subscriber(const std::vector<std::string>& names);
  void move_subscriber(dds::Subscriber* sub, const std::vector<std::string>& names);
  // A reader of `on` for the state stream, behind the roster filter.
  Reader make_reader(dds::Subscriber* sub, dds::Topic* on);
  void delete_reader(dds::Subscriber* sub, Reader& r);

  // Where its readers hear by place, and whom by name (`names`: agent partitions), judged in this
  // process as samples arrive (RosterFilterFactory::set_local_place).
  void set_place(const Interest& interest, const std::vector<std::string>& names);

 private:
  dds::DomainParticipant* participant_;
  StateBusOptions opts_;
  std::string type_name_;
  dds::Topic* shared_topic_;
  dds::DataReaderListener* listener_;
  RosterFilterFactory& roster_;
  dds::DataReaderQos reader_qos_;
  dds::DataWriterQos writer_qos_;
  struct Counted {
    dds::Topic* topic = nullptr;
    int users = 0;
  };
  std::map<std::string, Counted> topics_;
  bool place_told_ = false;
  PlaceFilter place_;
};

// A state or record writer's settings: no filtering on the writer's side (readers filter what
// they are sent), and a history that allocates nothing in steady state: one payload reserved, not
// Fast DDS's 100 (a writer keeps its agent's last sample, and an agent may write 8 region topics).
dds::DataWriterQos unfiltered(dds::DataWriterQos wq);

}  // namespace qswarm::state_bus
