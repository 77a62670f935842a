// Routing::kPartitions: one writer and one reader of the shared topic, whose partitions are the
// interest's names. Simple discovery matches every pair of participants anyway; a move updates
// each endpoint through discovery once.
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>

#include "common/dds/state_routes.hpp"

#include "swarm_state.h"

namespace qswarm::state_bus {

int StateRoute::region_readers_matched(const std::string&) const { return 0; }

namespace {

class PartitionsRoute final : public StateRoute {
 public:
  // The writer first, as its readers' peers expect; whatever was made goes again if a later
  // endpoint cannot be (a reader left behind would call into a bus that is gone).
  explicit PartitionsRoute(StateEndpoints& e) : e_(e) {
    try {
      if (e.opts().publish) writer_ = e.make_writer(e.shared_topic(), {}, e.opts().self);
      subscriber_ = e.make_subscriber({});
      reader_ = e.make_reader(subscriber_, e.shared_topic());
    } catch (...) {
      close();
      throw;
    }
  }
  ~PartitionsRoute() override { close(); }
  void set_interest(const Interest& interest) override {
    if (writer_.writer) e_.move_writer(writer_, interest.publish, e_.opts().self);
    // Names and cells are partitions of one topic: a sample heard by name passes whatever its
    // place.
    e_.set_place(interest, interest.subscribe);
    e_.move_subscriber(subscriber_, interest.subscribe);
  }
  std::optional<bool> write(qswarm_msgs::AgentState& sample) override {
    if (!writer_.writer) return std::nullopt;
    return writer_.writer->write(&sample);
  }
  int matched_readers() const override {
    return writer_.listener ? writer_.listener->matched.load() : 0;
  }

 private:
  void close() {
    if (subscriber_) {
      e_.delete_reader(subscriber_, reader_);
      e_.participant()->delete_subscriber(subscriber_);
      subscriber_ = nullptr;
    }
    e_.delete_writer(writer_);
  }
  StateEndpoints& e_;
  dds::Subscriber* subscriber_ = nullptr;
  Reader reader_;
  Writer writer_;
};

}  // namespace

std::unique_ptr<StateRoute> partitions_route(StateEndpoints& e) {
  return std::make_unique<PartitionsRoute>(e);
}

}  // namespace qswarm::state_bus
