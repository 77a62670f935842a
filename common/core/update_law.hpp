#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "common/core/agent.hpp"
#include "common/core/math.hpp"
#include "common/core/topology.hpp"

namespace qswarm {

// A cumulative flow the sender owns on edge (sender, peer): what the edge-flow law exchanges.
struct FlowEntry {
  AgentId peer = 0;
  Vec3 flow = Vec3::Zero();  // f_{sender,peer}: taken from the sender, given to the peer [m]
  double weight = 0.0;       // the edge's weight as the owner last computed it
  // A flow: the owner links the edge now (flows persist after it drops). A copy: its holder
  // heard the owner lately (NeighborView::current); the owner moves only while it says so.
  bool active = false;
};

// What an agent publishes and what its neighbours' laws read. Transport-independent.
struct NeighborView {
  AgentId id = 0;
  Vec3 q = Vec3::Zero();          // consensus state
  Vec3 q0 = Vec3::Zero();         // the sender's initial state q_j(0)
  double total_weight = 0.0;      // sum of the sender's link weights, as of its last tick
  std::vector<FlowEntry> flows;   // flows the sender owns (peer = the other end)
  std::vector<FlowEntry> copies;  // copies the sender holds of flows owned by others (peer = owner)
  // A restarted sender's question: the peers it hears whose flow or copy on their shared edge it
  // has not yet been told (edge-flow). Each answers with that entry, zero if it has none.
  std::vector<AgentId> asking;
  std::uint64_t seq = 0;  // sender's tick count: a new message has a larger one
  // The sender's law (law_tag of its name) and what that law alone sends its neighbours (its
  // LawSpec says how much): carried and checked like the fields above, read only by the same law.
  std::uint32_t law = 0;
  std::vector<double> payload;
  // Not on the wire: under TopologyPolicy::kRange the receiver's runtime sets the physical distance
  // between the two agents here, and links follow it instead of the states' distance.
  double link_distance_m = -1.0;
  // Not on the wire: whether the receiver's runtime heard this view lately (within two ticks, or a
  // quarter of the neighbour timeout if longer). A link forms only on a current view: a stale one
  // may show the neighbour where it no longer is (under neighbourhood delivery a neighbour that
  // moved out of reach falls silent, and the receiver, moving toward where it was last heard, would
  // link a ghost). A link that exists outlives a stale view until the neighbour timeout, as under
  // loss.
  bool current = true;
};

// The most doubles a law's payload may carry (the wire's bound; a law declares its own below it).
inline constexpr std::size_t kMaxLawPayload = 64;
// The largest magnitude a payload value may have.
inline constexpr double kMaxLawPayloadValue = 1e9;

// Returns an empty string if a received view is usable, else why not (NaN, absurd magnitude, ...).
// A law never sees a view that fails this: the runtime drops and counts it.
std::string check_view(const NeighborView& v, double max_abs_coordinate_m = 1e6);

struct LawConfig {
  // The law by name (common/laws/laws.inc lists them; find_law resolves aliases) and its
  // parameters by name: make_law checks them and fills the rest from the law's LawSpec.
  std::string law = "edge-flow";
  std::map<std::string, double> params;
  WeightConfig weight;
  TopologyConfig topology;
  double gain = 1.0;  // k: time scale of the agreement [1/s per unit weight]
  // s: the most a tick may move an agent, as a fraction of the way to its neighbours' weighted
  // mean. Below 1/2 the step survives a tick or two of message delay (see UpdateLaw).
  double max_step_fraction = 0.3;
  void validate() const;
};

// The per-agent agreement law: the same object runs in the in-process swarm and in each agent
// process. Discretisation: one tick of length dt moves along each edge by
//   c_ij = (w_ij / W) min(1 - exp(-k W dt), s),   W = max(W_i, W_j, w_ij)
// where W_i, W_j are the endpoints' published total weights and s the max step fraction. The row
// sums of c are then below s for any weights and dt, so a tick is a convex combination (stable for
// the paper's large distance weights), c_ij = c_ji when both ends see the same snapshot, and
// c_ij -> k w_ij dt as dt -> 0 (the paper's ODE). s < 1/2 matters between processes: a neighbour's
// state is up to a tick old, and x' = x - g x(t - dt) is stable only for g < 1, while the step's
// Laplacian has eigenvalues up to 2s. With s near 1 and distance weights, a 12-agent swarm over DDS
// diverged (weights grow with the error it makes).
class UpdateLaw {
 public:
  UpdateLaw(AgentId self, const Vec3& q0, LawConfig cfg);
  virtual ~UpdateLaw() = default;

  // Update links and weights from the neighbours' latest views without moving (start of a run).
  void observe(const std::vector<NeighborView>& neighbors);
  // One tick of dt seconds given the latest (already checked) view of each live neighbour. A
  // neighbour absent from the list is treated as silent: its link is dropped (flows stay).
  void step(double dt_s, const std::vector<NeighborView>& neighbors);

  AgentId id() const { return self_; }
  const Vec3& initial_state() const { return q0_; }
  virtual Vec3 state() const = 0;
  // The message to publish after a tick.
  NeighborView message() const;
  // Current links and their weights, as this agent sees them.
  const std::map<AgentId, double>& links() const { return links_; }
  double total_weight() const { return published_total_weight_; }
  const LawConfig& config() const { return cfg_; }
  virtual std::vector<FlowEntry> owned_flows() const { return {}; }
  virtual std::vector<FlowEntry> held_copies() const { return {}; }
  // After a restart: take back the flows this agent owned from its neighbours' copies, so that
  // its state, and the swarm's total, are what they were (recovered_count() says how many flows).
  // Recovery continues lazily: an owned neighbour first heard later is recovered then.
  virtual void recover(const std::vector<NeighborView>&) {}
  virtual int recovered_count() const { return 0; }
  // Neighbour values the law ignored since it started (W-MSR's trimming; 0 for the others).
  virtual std::uint64_t trimmed_total() const { return 0; }
  // Peers whose link is gone but whose exchange with this agent is not settled yet (edge-flow: a
  // flow the other end has not shown back, a copy its owner still announces): the two must keep
  // hearing each other until it is, or the swarm's total moves.
  virtual std::set<AgentId> settling() const { return {}; }

 protected:
  // What a tick moves along: `coef[k]` is c for neighbours[k] (0 when not linked), `weight[k]`
  // its link's weight w (0 when not linked), dt the tick's length.
  struct Tick {
    const std::vector<NeighborView>& neighbors;
    const std::vector<double>& coef;
    const std::vector<double>& weight;
    double dt_s;
  };
  virtual void integrate(const Tick& t) = 0;
  // After observe() has set the first links, before the first message goes out.
  virtual void links_observed() {}
  // What the agent asks its peers (NeighborView::asking).
  virtual std::vector<AgentId> asking() const { return {}; }
  // What the law sends its neighbours beside the consensus state (NeighborView::payload), at most
  // its LawSpec::payload_max values.
  virtual std::vector<double> payload() const { return {}; }
  std::vector<double> update_links(const std::vector<NeighborView>& neighbors);

  AgentId self_;
  Vec3 q0_;
  LawConfig cfg_;
  LinkTracker tracker_;
  std::map<AgentId, double> links_;
  double published_total_weight_ = 0.0;
  bool observed_ = false;
  std::uint64_t ticks_ = 0;
  std::uint32_t law_tag_ = 0;
  std::size_t payload_max_ = kMaxLawPayload;  // its LawSpec's, set by make_law

 private:
  friend std::unique_ptr<UpdateLaw> make_law(AgentId self, const Vec3& q0, const LawConfig& cfg);
};

// The law cfg.law names, from its LawSpec, with cfg.params checked and completed (throws
// std::invalid_argument naming what is wrong).
std::unique_ptr<UpdateLaw> make_law(AgentId self, const Vec3& q0, const LawConfig& cfg);

class LaplacianLaw final : public UpdateLaw {
 public:
  LaplacianLaw(AgentId self, const Vec3& q0, LawConfig cfg)
      : UpdateLaw(self, q0, std::move(cfg)), q_(q0) {}
  Vec3 state() const override { return q_; }

 private:
  void integrate(const Tick& t) override;
  Vec3 q_;
};

// W-MSR (weighted mean-subsequence-reduced; LeBlanc, Zhang, Koutsoukos, Sundaram, IEEE JSAC 2013):
// each tick and each coordinate, of the linked neighbours' values drop the F largest of those above
// one's own (all of them when there are fewer) and the F smallest of those below, then take the
// Laplacian step over the rest, normalised by the kept weights only (a liar's weight cannot slow
// the honest step). If at most F agents lie, in total, and the graph is (F+1, F+1)-robust, the
// honest agents agree inside the range of their initial values, per coordinate: for positions,
// inside the honest initial values' bounding box, not their convex hull. The price: no exact
// average (trimming is not symmetric), so the agreed point depends on the run.
class WmsrLaw final : public UpdateLaw {
 public:
  WmsrLaw(AgentId self, const Vec3& q0, LawConfig cfg);
  Vec3 state() const override { return q_; }
  // Neighbour values trimmed on the last tick (all coordinates together), and since the start.
  std::uint64_t trimmed() const { return trimmed_; }
  std::uint64_t trimmed_total() const override { return trimmed_total_; }

 private:
  void integrate(const Tick& t) override;
  Vec3 q_;
  std::size_t f_;  // the liars tolerated (parameter "f")
  std::uint64_t trimmed_ = 0;
  std::uint64_t trimmed_total_ = 0;
  struct Value {
    double v;
    double w;
  };
  std::vector<Value> scratch_;  // reused: a tick allocates nothing in steady state
};

// q_i = q_i(0) - sum_{owned} f_ij + sum_{copies} f_ki. The owner integrates f_ij; the other end
// applies the newest copy it received, so the sum over agents is exact whenever copies are current.
// Between copies the non-owner predicts the owner's increments with the same formula (what the
// Laplacian law would do) and drops the prediction when a newer copy arrives: the prediction
// removes the one-message lag, the copy keeps the total exact. In lockstep the two laws then
// coincide.
//
// A message carries only the entries that still matter, so its size follows the agent's degree,
// not its history: the owner announces a flow while the edge is linked, until the other end has
// shown a copy equal to it (settled), and whenever the other end asks for it; the other end shows
// its copy while the edge is linked, while the owner still announces the flow, and when the owner
// asks. A copy says whether its holder heard the owner lately (FlowEntry::active), and an owner
// moves on an edge only while the other end's newest message says so: where only one end hears
// the other (a one-sided DDS match), nothing moves that the other end could never take in. A cut
// in one direction mid-run still lets the owner move until the other end's view of it goes stale
// (two ticks, or a quarter of the neighbour timeout if longer): taken in if the cut heals, lost if
// it never does. An owner moves about once per message of the other end's, so a neighbour that
// stalls (a late tick, a stopped process) takes in three steps at most when it wakes, not one per
// tick it slept, which would throw it past its neighbours. An owner announces a linked edge, moved
// on or not, and the other end predicts only while the owner links it and its own last message said
// it heard the owner, so in lockstep the two laws still coincide on a fixed graph; a link that
// forms mid-run moves one tick later than the Laplacian law's. Settled entries stay in both agents'
// states. A restarted agent has lost its half of every edge it had: it asks each peer it hears
// until that peer has answered (an owner adopts the copy before it moves on the edge again; a
// non-owner takes the owner's flow as a copy), so a restart never moves the total.
class EdgeFlowLaw final : public UpdateLaw {
 public:
  EdgeFlowLaw(AgentId self, const Vec3& q0, LawConfig cfg) : UpdateLaw(self, q0, std::move(cfg)) {}
  Vec3 state() const override;
  std::vector<FlowEntry> owned_flows() const override;
  std::vector<FlowEntry> held_copies() const override;
  std::set<AgentId> settling() const override;
  void recover(const std::vector<NeighborView>& neighbors) override;
  int recovered_count() const override { return recovered_; }
  bool owns(AgentId peer) const { return self_ < peer; }
  // Flows and copies this agent holds, settled or not (its state's history).
  std::size_t held_entries() const { return owned_.size() + copies_.size(); }

 protected:
  std::vector<AgentId> asking() const override;

 private:
  void integrate(const Tick& t) override;
  void links_observed() override;
  // An owner moves once per message of the other end's, at most three in hand (two after the
  // tick's move): with a full hand a tick's jitter or two lost messages in a row cost no move, and
  // a stalled neighbour has three moves to take in when it wakes (at the default max_step_fraction
  // of 0.3, 0.9 of the way to its neighbours; the bound assumes a fraction of at most 1/3).
  static constexpr int kMoveCredit = 3;
  struct Owned {
    FlowEntry entry;
    bool settled = false;         // the other end showed a copy equal to it since it last changed
    bool heard = false;           // read a message of the other end's since the entry was made
    std::uint64_t heard_seq = 0;  // the last one read (smaller after the other end restarts)
    int credit = kMoveCredit;     // moves the other end's messages allow yet
  };
  // Messages of the other end's since `o` last read one (up to kMoveCredit).
  static int messages_since(const Owned& o, std::uint64_t seq);
  struct Copy {
    Vec3 flow = Vec3::Zero();       // newest f_{owner,self} received
    Vec3 predicted = Vec3::Zero();  // our estimate of the owner's increments since that copy
    std::uint64_t seq = 0;          // message it came in
    bool seen = false;
    bool announced = false;    // the owner's newest message carried this edge's flow
    bool linked = false;       // linked on the last tick
    bool hearing = false;      // heard the owner lately on the last tick: the copy's active
    bool was_hearing = false;  // the same a tick before: what the owner last read (integrate)
    // Since the link last ended, a message of the owner's carried no flow for this edge: the owner
    // has settled it (or never moved on it), nothing is left to hear.
    bool quiet = false;
  };
  std::map<AgentId, Owned> owned_;  // edges this agent owns (peer id > self)
  std::map<AgentId, Copy> copies_;  // flows neighbours own toward us
  // Whether the newest message shows this copy (held_copies()).
  bool shows(AgentId owner, const Copy& c) const;
  std::set<AgentId> askers_;  // peers whose newest message asks this agent
  bool recovering_ = false;   // restarted: ask each peer heard until it answered
  std::set<AgentId> answered_;
  std::set<AgentId> unanswered_;  // heard on the last tick, not answered yet
  int recovered_ = 0;
  // Takes a peer's answer (its entry about this agent) if its message has one.
  bool take_answer(const NeighborView& v);
};

}  // namespace qswarm
