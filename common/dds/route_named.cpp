// Routing::kNamedTopics and kRegionTopics, for a Discovery Server's clients: the server relays a
// participant's announcement only to participants with an endpoint on a topic it uses (partitions
// are matched by the clients, after discovery), so an agent that hears its neighbours by name
// (a FIXED graph) discovers only them when each agent name is a topic of its own. Cells stay
// partitions of the shared topic, or of their region's topic (RegionEndpoints), rather than
// topics of their own: a move between topics would replace the writer, and its readers would
// hear it only once the server had relayed the new one. No writer is bound to its agent here
// (Fast DDS 2.9 has no secure Discovery Server); the gate judges a sample's participant, since
// an agent speaks through several writers.
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>

#include <algorithm>
#include <optional>
#include <set>
#include <stdexcept>

#include "common/dds/state_routes.hpp"

#include "swarm_state.h"

namespace qswarm::state_bus {
namespace {

bool has(const std::vector<std::string>& v, const std::string& n) {
  return std::find(v.begin(), v.end(), n) != v.end();
}

class NamedRoute final : public StateRoute {
 public:
  NamedRoute(StateEndpoints& e, bool regions)
      : e_(e), subscriber_(e.make_subscriber({})), named_subscriber_(e.make_subscriber({})) {
    if (regions) regions_.emplace(e, subscriber_);
  }
  ~NamedRoute() override {
    e_.delete_reader(subscriber_, shared_reader_);
    regions_.reset();
    for (auto& [name, r] : readers_) drop_reader(name, r);
    for (auto& [name, w] : writers_) drop_writer(name, w);
    e_.delete_writer(shared_writer_);
    e_.participant()->delete_subscriber(named_subscriber_);
    e_.participant()->delete_subscriber(subscriber_);
  }

  void set_interest(const Interest& interest) override;

  std::optional<bool> write(qswarm_msgs::AgentState& sample) override {
    if (!told_) set_interest({});  // endpoints come with the interest: the whole run until told
    if (!shared_writer_.writer && writers_.empty() && !(regions_ && regions_->writers()))
      return std::nullopt;
    bool written = !shared_writer_.writer || shared_writer_.writer->write(&sample);
    for (auto& [name, w] : writers_)  // an agent name nobody listens to costs nothing
      if (w.listener->matched > 0) written = w.writer->write(&sample) && written;
    if (regions_) written = regions_->write(sample) && written;
    return written;
  }

  int matched_readers() const override {
    int n = shared_writer_.listener ? shared_writer_.listener->matched.load() : 0;
    for (const auto& [name, w] : writers_) n += w.listener->matched;
    if (regions_) n += regions_->matched_readers();
    return n;
  }
  int region_readers_matched(const std::string& region) const override {
    return regions_ ? regions_->readers_matched(region) : 0;
  }

 private:
  void drop_reader(const std::string& name, Reader& r) {
    e_.delete_reader(named_subscriber_, r);
    e_.release_topic(name);
  }
  void drop_writer(const std::string& name, Writer& w) {
    e_.delete_writer(w);
    e_.release_topic(name);
  }

  StateEndpoints& e_;
  dds::Subscriber* subscriber_;        // the shared topic's reader and the regions' readers
  dds::Subscriber* named_subscriber_;  // the names' readers, in the run's partition
  Writer shared_writer_;
  Reader shared_reader_;
  std::map<std::string, Writer> writers_;  // the agent names'
  std::map<std::string, Reader> readers_;
  std::optional<RegionEndpoints> regions_;
  bool told_ = false;
};

void NamedRoute::set_interest(const Interest& interest) {
  told_ = true;
  const bool publish = e_.opts().publish;
  const auto named = [](const std::string& n) {
    return agent_of_partition(n).has_value() || inbox_of_partition(n).has_value();
  };
  // Regions for the cells of one space only: with two (proximity and collision avoidance) a
  // sample would go out once per space's region, and a listener of both would count it twice.
  std::set<char> spaces;
  for (const auto* names : {&interest.publish, &interest.subscribe})
    for (const std::string& n : *names)
      if (region_of_cell(n)) spaces.insert(n[0]);
  const auto cell = [&](const std::string& n) {
    return regions_ && spaces.size() == 1 && region_of_cell(n).has_value();
  };
  std::vector<std::string> agents_pub, cells_pub, shared_pub, agents_sub, cells_sub, shared_sub;
  for (const std::string& n : interest.publish)
    (named(n) ? agents_pub : cell(n) ? cells_pub : shared_pub).push_back(n);
  for (const std::string& n : interest.subscribe)
    (named(n) ? agents_sub : cell(n) ? cells_sub : shared_sub).push_back(n);
  // The place judges what the names' own topics bring too: it names them, so that a sample heard
  // by name passes wherever it is.
  e_.set_place(interest, agents_sub);
  // The shared topic carries the other names, and the whole run (the empty interest). Its
  // endpoints are made once needed, in their partitions: they never hear the whole run on the way.
  if (publish && (interest.publish.empty() || !shared_pub.empty())) {
    if (shared_writer_.writer)
      e_.move_writer(shared_writer_, shared_pub);
    else
      shared_writer_ = e_.make_writer(e_.shared_topic(), shared_pub);
  } else {
    e_.delete_writer(shared_writer_);
    shared_writer_.listener.reset();
  }
  const bool shared_reader = interest.subscribe.empty() || !shared_sub.empty();
  if (shared_reader && !cells_sub.empty())  // the subscriber's partitions are the cells'
    throw std::invalid_argument("dds: an interest listens to cells and to names of no cell");
  if (regions_) regions_->drop_readers_beyond(cells_sub);
  if (shared_reader) {
    e_.move_subscriber(subscriber_, shared_sub);
    if (!shared_reader_.reader) shared_reader_ = e_.make_reader(subscriber_, e_.shared_topic());
  } else {
    e_.delete_reader(subscriber_, shared_reader_);
  }
  if (regions_) regions_->set(publish ? cells_pub : std::vector<std::string>{}, cells_sub);
  // The agent names: new endpoints first, then the old ones go.
  for (const std::string& n : agents_sub)
    if (!readers_.count(n))
      readers_.emplace(
          n, e_.on_topic(n, [&](dds::Topic* t) { return e_.make_reader(named_subscriber_, t); }));
  if (publish)
    for (const std::string& n : agents_pub)
      if (!writers_.count(n))
        writers_.emplace(n, e_.on_topic(n, [&](dds::Topic* t) { return e_.make_writer(t, {}); }));
  for (auto it = readers_.begin(); it != readers_.end();) {
    if (has(agents_sub, it->first)) {
      ++it;
      continue;
    }
    drop_reader(it->first, it->second);
    it = readers_.erase(it);
  }
  for (auto it = writers_.begin(); it != writers_.end();) {
    if (has(agents_pub, it->first)) {
      ++it;
      continue;
    }
    drop_writer(it->first, it->second);
    it = writers_.erase(it);
  }
}

}  // namespace

std::unique_ptr<StateRoute> named_route(StateEndpoints& e, bool regions) {
  return std::make_unique<NamedRoute>(e, regions);
}

}  // namespace qswarm::state_bus
