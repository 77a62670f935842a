// Routing::kRegionTopics' cells: partitions of their region's topic (region_of_cell), so that
// through a Discovery Server an agent discovers the agents of the regions about it, not the swarm.
// Each move updates up to 8 readers and several writers through the server instead of one of
// each, which the server's hang in Fast DDS 2.9.1 makes a risk (docs/fast-dds-workarounds.md, W5):
// worth it only where the shared topic cannot discover at all (RunPlan: past 128 agents).
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>

#include <algorithm>
#include <set>

#include "common/dds/state_routes.hpp"

#include "swarm_state.h"

namespace qswarm::state_bus {

RegionEndpoints::~RegionEndpoints() {
  while (!readers_.empty()) drop(readers_.begin()->first, true, true);
  while (!writers_.empty()) drop(writers_.begin()->first, true, true);
}

void RegionEndpoints::drop(const std::string& region, bool its_reader, bool its_writer) {
  if (auto r = readers_.find(region); its_reader && r != readers_.end()) {
    e_.delete_reader(sub_, r->second);
    readers_.erase(r);
    e_.release_topic(region);
  }
  if (auto w = writers_.find(region); its_writer && w != writers_.end()) {
    e_.delete_writer(w->second.w);
    writers_.erase(w);
    e_.release_topic(region);
  }
}

void RegionEndpoints::drop_readers_beyond(const std::vector<std::string>& cells) {
  std::set<std::string> regions;
  for (const std::string& c : cells) regions.insert(*region_of_cell(c));
  std::vector<std::string> gone;
  for (const auto& [region, r] : readers_)
    if (!regions.count(region)) gone.push_back(region);
  for (const std::string& region : gone) drop(region, true, false);
}

void RegionEndpoints::set(const std::vector<std::string>& pub,
                          const std::vector<std::string>& sub) {
  // Readers: those that go are gone (drop_readers_beyond); the subscriber's partitions are every
  // listened cell, whatever the region (a writer of one region never publishes another's cells),
  // and the new ones come with them.
  std::set<std::string> regions;
  for (const std::string& c : sub) regions.insert(*region_of_cell(c));
  if (!sub.empty()) e_.move_subscriber(sub_, sub);
  for (const std::string& region : regions)
    if (!readers_.count(region))
      readers_.emplace(region,
                       e_.on_topic(region, [&](dds::Topic* t) { return e_.make_reader(sub_, t); }));

  // Writers: the cells each region's writer publishes into, those of the active ones first.
  std::map<std::string, std::pair<std::vector<std::string>, bool>> want;  // region: cells, active
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
  for (auto& [region, w] : want) {
    auto& [cells, active] = w;
    std::sort(cells.begin(), cells.end());
    cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
    if (auto it = writers_.find(region); it != writers_.end()) {
      it->second.active = active;
      if (it->second.w.names != cells) e_.move_writer(it->second.w, cells);
      continue;
    }
    RegionWriter rw;
    const std::vector<std::string>& partitions = cells;  // a lambda captures no structured binding
    rw.w = e_.on_topic(region, [&](dds::Topic* t) { return e_.make_writer(t, partitions); });
    rw.active = active;
    writers_.emplace(region, std::move(rw));
  }
  std::vector<std::string> gone;
  for (const auto& [region, w] : writers_)
    if (!want.count(region)) gone.push_back(region);
  for (const std::string& region : gone) drop(region, false, true);
}

bool RegionEndpoints::write(qswarm_msgs::AgentState& sample) {
  bool written = true;
  for (auto& [region, rw] : writers_)
    if (rw.active && rw.w.listener->matched > 0) written = rw.w.writer->write(&sample) && written;
  return written;
}

int RegionEndpoints::matched_readers() const {
  int n = 0;
  for (const auto& [region, rw] : writers_)
    if (rw.active) n += rw.w.listener->matched;
  return n;
}

int RegionEndpoints::readers_matched(const std::string& region) const {
  const auto it = writers_.find(region);
  return it == writers_.end() ? 0 : it->second.w.listener->matched.load();
}

}  // namespace qswarm::state_bus
