#pragma once

#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "common/core/agent.hpp"
#include "common/core/math.hpp"
#include "common/scenario/run_config.hpp"
#include "proto/records.pb.h"

namespace qswarm {

// What a scene needs beyond the samples and the graph: where the swarm should meet and, in a
// formation, each agent's slot about the agreed point.
struct SceneSettings {
  Vec3 initial_average = Vec3::Zero();  // the ideal agreement point (the average of q(0))
  std::map<AgentId, Vec3> offsets;      // formation slots about the centre; empty: no formation
  std::string frame_id = "world";       // the frame every entity is drawn in

  // The run's initial average, and its slots if it flies a formation.
  static SceneSettings of(const RunConfig& rc);
};

// The swarm as a Foxglove 3D scene: one foxglove.SceneUpdate message (JSON encoding, schema
// scene_update_json_schema()) that first deletes every entity of the topic, then draws the whole
// swarm at the snapshot's time, so that any one message (after a seek, to a client that just
// connected) is the full picture. Entities:
//   agent/ID         a sphere at its position, an arrow along its body x axis (its heading, for
//                    quadcopters) and its id as text
//   links            the snapshot's edges between the agents' positions, in five classes of weight
//                    from blue (the lightest fifth) to red (the heaviest), each class one line list
//                    (metadata: t_s, lambda2, edges, disagreement_m, weight_min, weight_max)
//   agreement        the mean of the agents' consensus states (green)
//   initial_average  the ideal agreement point (white, translucent)
//   slot/ID          with a formation: the agent's slot, the agreement point plus its offset
// Agents without a finite position, and edges to agents without a sample, are left out.
std::string scene_update_json(const std::vector<records::AgentSample>& agents,
                              const records::GraphSnapshot& graph, const SceneSettings& settings);

// The JSON schema of foxglove.SceneUpdate, as far as scene_update_json uses it: the Schema data of
// the scene channel (schema encoding "jsonschema").
std::string_view scene_update_json_schema();

// Keeps the latest sample of every agent present and makes the scene for a graph snapshot: what
// the recorder, `swarm export` and a live view feed with the record's own stream (samples, events,
// snapshots), in that stream's order.
class SceneBuilder {
 public:
  explicit SceneBuilder(SceneSettings settings) : settings_(std::move(settings)) {}

  void on_sample(const records::AgentSample& s) { latest_[s.id()] = s; }
  // A departure ("depart") takes the agent out of the scene until it is heard again.
  void on_event(const records::Event& e);
  // The scene at the snapshot's time.
  std::string scene_json(const records::GraphSnapshot& graph) const;
  std::size_t agents() const { return latest_.size(); }

 private:
  SceneSettings settings_;
  std::map<AgentId, records::AgentSample> latest_;
};

}  // namespace qswarm
