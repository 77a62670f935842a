#pragma once

namespace qswarm {

// How the state stream reaches those who hear it (RunPlan::routing, StateBusOptions::routing).
enum class Routing {
  // One topic; the names and cells of an interest are its partitions. Simple discovery matches
  // every pair of participants anyway.
  kPartitions,
  // Through a Discovery Server, which relays a participant only to those sharing a topic with it:
  // agent names are topics of their own, so an agent that hears its neighbours by name discovers
  // only them; cells stay partitions of the one topic.
  kNamedTopics,
  // As kNamedTopics, and cells are partitions of their region's topic, so an agent that hears by
  // place discovers the agents of the regions about it, not the swarm.
  kRegionTopics,
};

inline const char* to_string(Routing r) {
  switch (r) {
    case Routing::kNamedTopics:
      return "named-topics";
    case Routing::kRegionTopics:
      return "region-topics";
    case Routing::kPartitions:
      break;
  }
  return "partitions";
}

}  // namespace qswarm
