#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "common/transport/neighbor_bus.hpp"

namespace qswarm {

// The fault plan of a run (scenario `faults`, validated). Times in simulated seconds; end 0 =
// until the end; agent 0 = any agent.
struct FaultPlan {
  struct Loss {
    double probability = 0.0;
    AgentId from = 0, to = 0;
    double start_s = 0.0, end_s = 0.0;
  };
  struct Burst {
    double p_good_to_bad = 0.0, p_bad_to_good = 1.0, loss_good = 0.0, loss_bad = 1.0;
    AgentId from = 0, to = 0;
  };
  struct Cut {
    AgentId a = 0, b = 0;
    double start_s = 0.0, end_s = 0.0;
    bool directed = false;
  };
  struct Partition {
    std::vector<AgentId> group;
    double start_s = 0.0, end_s = 0.0;
  };
  struct Delay {
    double mean_s = 0.0, jitter_s = 0.0;
    AgentId from = 0, to = 0;
  };
  struct Kill {
    AgentId agent = 0;
    double at_s = 0.0, restart_at_s = 0.0;  // restart 0: stays dead
  };
  struct LateJoin {
    AgentId agent = 0;
    double at_s = 0.0;
  };
  std::vector<Loss> loss;
  std::vector<Burst> burst;
  std::vector<Cut> cut;
  std::vector<Partition> partition;
  std::vector<Delay> delay;
  std::vector<Kill> kill;
  std::vector<LateJoin> late_join;
  std::uint32_t transport_drop_percent = 0;

  bool empty() const;
  // When the swarm's last link fault ends (cuts, partitions, kills' restarts), for reconvergence.
  double last_fault_end_s() const;
  // A timed event list for the record: (time, kind, agent, detail).
  struct Event {
    double t_s;
    std::string kind;
    AgentId agent;
    std::string detail;
  };
  std::vector<Event> timeline() const;
};

// Counts of injected faults (per agent, published in its state and summed in the summary).
struct FaultCounters {
  std::uint64_t loss = 0, burst = 0, cut = 0, partition = 0, delayed = 0;
  std::uint64_t dropped() const { return loss + burst + cut + partition; }
};

// Decides, for every message arriving at agent `self`, whether the plan drops or delays it. One
// random stream per directed link, seeded from (seed, from, self): a run replays. Pure.
class LinkFaults {
 public:
  LinkFaults(FaultPlan plan, AgentId self, std::uint64_t seed);
  struct Verdict {
    bool drop = false;
    double delay_s = 0.0;
  };
  Verdict on_receive(AgentId from, double t_s);
  const FaultCounters& counters() const { return counters_; }
  bool cut_now(AgentId from, double t_s) const;

 private:
  struct Link {
    std::mt19937_64 rng;
    std::vector<bool> bad;  // Gilbert-Elliott state per burst entry
  };
  Link& link(AgentId from);
  FaultPlan plan_;
  AgentId self_;
  std::uint64_t seed_;
  std::map<AgentId, Link> links_;
  FaultCounters counters_;
  std::vector<double> draws_;
};

// The fault-injecting NeighborBus: samples from an inner bus's delivery pass through LinkFaults
// (drop, or hold until a delay elapses) before the agent can read them. Publishing goes straight
// to the inner bus. Thread-safe: deliver() may run on a transport thread.
class FaultyBus final : public NeighborBus {
 public:
  FaultyBus(NeighborBus& inner, LinkFaults faults, AgentId self);
  // Feed every sample received by the inner transport (e.g. DdsBus's sample callback).
  void deliver(const StateMessage& m);
  void set_time(double t_s);
  void publish(const StateMessage& msg) override { inner_.publish(msg); }
  std::vector<StateMessage> latest(AgentId self) override;
  FaultCounters counters() const;

 private:
  void release_due_locked();
  NeighborBus& inner_;
  LinkFaults faults_;
  AgentId self_;
  mutable std::mutex mu_;
  double t_s_ = 0.0;
  std::multimap<double, StateMessage> held_;  // release time -> message
  std::map<AgentId, StateMessage> latest_;
};

std::uint64_t link_seed(std::uint64_t seed, AgentId from, AgentId to);

}  // namespace qswarm
