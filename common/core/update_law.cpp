#include "common/core/update_law.hpp"

#include "common/core/law_registry.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace qswarm {

std::string check_view(const NeighborView& v, double max_abs) {
  const auto bad_vec = [&](const Vec3& x) {
    return !x.allFinite() || x.cwiseAbs().maxCoeff() > max_abs;
  };
  if (bad_vec(v.q))
    return "consensus state not finite or beyond +-" + std::to_string(max_abs) + " m";
  if (bad_vec(v.q0)) return "initial state not finite or absurd";
  if (!std::isfinite(v.total_weight) || v.total_weight < 0.0 || v.total_weight > 1e9) {
    return "total weight not finite, negative or absurd";
  }
  for (const FlowEntry& f : v.flows) {
    if (bad_vec(f.flow)) return "flow not finite or absurd";
    if (!std::isfinite(f.weight) || f.weight < 0.0 || f.weight > 1e9) return "flow weight invalid";
    if (f.peer == v.id) return "flow to itself";
  }
  for (const FlowEntry& f : v.copies) {
    if (bad_vec(f.flow)) return "copy not finite or absurd";
    if (f.peer == v.id) return "copy of its own flow";
  }
  for (const AgentId a : v.asking)
    if (a == 0 || a == v.id) return "asks agent 0 or itself";
  if (v.payload.size() > kMaxLawPayload) return "law payload longer than the wire's bound";
  for (const double x : v.payload)
    if (!std::isfinite(x) || std::abs(x) > kMaxLawPayloadValue)
      return "law payload not finite or absurd";
  return {};
}

void LawConfig::validate() const {
  if (!std::isfinite(gain) || gain <= 0.0) {
    throw std::invalid_argument("law.gain = " + std::to_string(gain) +
                                ": expected a finite value > 0");
  }
  if (!std::isfinite(max_step_fraction) || max_step_fraction <= 0.0 || max_step_fraction > 1.0) {
    throw std::invalid_argument("law.max_step_fraction = " + std::to_string(max_step_fraction) +
                                ": expected a value in (0, 1]");
  }
  if (!std::isfinite(weight.scale) || weight.scale <= 0.0) {
    throw std::invalid_argument("weight.scale: expected a finite value > 0");
  }
}

UpdateLaw::UpdateLaw(AgentId self, const Vec3& q0, LawConfig cfg)
    : self_(self),
      q0_(q0),
      cfg_(std::move(cfg)),
      tracker_(self, cfg_.topology),
      law_tag_(law_tag(cfg_.law)) {
  cfg_.validate();
  if (!q0.allFinite()) throw std::invalid_argument("initial state: expected finite coordinates");
}

std::vector<double> UpdateLaw::update_links(const std::vector<NeighborView>& neighbors) {
  const Vec3 q = state();
  std::map<AgentId, double> next;
  std::vector<double> weights(neighbors.size(), 0.0);
  for (size_t k = 0; k < neighbors.size(); ++k) {
    const NeighborView& n = neighbors[k];
    if (n.id == self_) continue;
    const double d = (q - n.q).norm();
    const bool by_range = cfg_.topology.policy == TopologyPolicy::kRange;
    // Under kRange a view without a physical distance (not set by the runtime) is not linked.
    if (by_range && !(n.link_distance_m >= 0.0)) continue;
    if (!n.current && !links_.count(n.id)) continue;
    if (!tracker_.update(n.id, by_range ? n.link_distance_m : d)) continue;
    // The paper's "weights due to initial distance" use |q_i(0) - q_j(0)|, whenever the link forms.
    const double w = weight_for_distance(
        cfg_.weight,
        cfg_.weight.policy == WeightPolicy::kInitialDistance ? (q0_ - n.q0).norm() : d);
    next[n.id] = w;
    weights[k] = w;
  }
  for (const auto& [peer, w] : links_) {
    if (!next.count(peer)) tracker_.forget(peer);
  }
  links_ = std::move(next);
  return weights;
}

void UpdateLaw::observe(const std::vector<NeighborView>& neighbors) {
  update_links(neighbors);
  ++ticks_;
  published_total_weight_ = 0.0;
  for (const auto& [peer, w] : links_) published_total_weight_ += w;
  observed_ = true;
  links_observed();
}

void UpdateLaw::step(double dt, const std::vector<NeighborView>& neighbors) {
  if (!std::isfinite(dt) || dt <= 0.0) throw std::invalid_argument("step: dt must be > 0");
  const std::vector<double> w = update_links(neighbors);
  double w_now = 0.0;
  for (double x : w) w_now += x;
  // Before the first publication the own total is unknown to peers; use the current one.
  const double w_self = observed_ ? published_total_weight_ : w_now;
  std::vector<double> coef(neighbors.size(), 0.0);
  for (size_t k = 0; k < neighbors.size(); ++k) {
    if (w[k] <= 0.0) continue;
    const double W = std::max({w_self, neighbors[k].total_weight, w[k]});
    const double s = cfg_.max_step_fraction;
    coef[k] = w[k] / W * std::min(-std::expm1(-cfg_.gain * W * dt), s);
  }
  integrate({neighbors, coef, w, dt});
  ++ticks_;
  published_total_weight_ = w_now;
  observed_ = true;
}

NeighborView UpdateLaw::message() const {
  NeighborView v;
  v.id = self_;
  v.q = state();
  v.q0 = q0_;
  v.total_weight = published_total_weight_;
  v.flows = owned_flows();
  v.copies = held_copies();
  v.asking = asking();
  v.seq = ticks_;
  v.law = law_tag_;
  v.payload = payload();
  // A law that sends what its receivers' gates refuse would fly alone: a programming error, said
  // where it is made (the agent exits, the kit marks the flight).
  if (v.payload.size() > payload_max_) {
    throw std::logic_error("law " + cfg_.law + " sent " + std::to_string(v.payload.size()) +
                           " payload values, more than the " + std::to_string(payload_max_) +
                           " its LawSpec declares");
  }
  for (const double x : v.payload) {
    if (!std::isfinite(x) || std::abs(x) > kMaxLawPayloadValue)
      throw std::logic_error("law " + cfg_.law + " sent a payload value not finite or beyond 1e9");
  }
  return v;
}

std::unique_ptr<UpdateLaw> make_law(AgentId self, const Vec3& q0, const LawConfig& cfg) {
  const LawSpec& spec = find_law(cfg.law);
  LawConfig resolved = cfg;
  resolved.law = spec.name;
  resolved.params = resolve_law_params(spec, cfg.params, "law.params");
  std::unique_ptr<UpdateLaw> law = spec.make(self, q0, resolved);
  law->payload_max_ = spec.payload_max;
  return law;
}

void LaplacianLaw::integrate(const Tick& t) {
  Vec3 dq = Vec3::Zero();
  for (size_t k = 0; k < t.neighbors.size(); ++k) dq -= t.coef[k] * (q_ - t.neighbors[k].q);
  q_ += dq;
}

WmsrLaw::WmsrLaw(AgentId self, const Vec3& q0, LawConfig cfg)
    : UpdateLaw(self, q0, std::move(cfg)),
      q_(q0),
      f_(static_cast<std::size_t>(resolve_law_params(find_law(cfg_.law), cfg_.params).at("f"))) {}

void WmsrLaw::integrate(const Tick& t) {
  const std::size_t F = f_;
  const double s = cfg_.max_step_fraction;
  trimmed_ = 0;
  Vec3 next = q_;
  for (int d = 0; d < 3; ++d) {
    const double own = q_[d];
    scratch_.clear();
    for (size_t k = 0; k < t.neighbors.size(); ++k)
      if (t.weight[k] > 0.0) scratch_.push_back({t.neighbors[k].q[d], t.weight[k]});
    std::sort(scratch_.begin(), scratch_.end(),
              [](const Value& a, const Value& b) { return a.v < b.v; });
    // scratch_[lo, hi) survives: at most F of the values below own cut from the front, at most F
    // of those above from the back.
    std::size_t below = 0, above = 0;
    for (const Value& x : scratch_) {
      below += x.v < own ? 1 : 0;
      above += x.v > own ? 1 : 0;
    }
    const std::size_t lo = std::min(below, F);
    const std::size_t hi = scratch_.size() - std::min(above, F);
    trimmed_ += lo + (scratch_.size() - hi);
    trimmed_total_ += lo + (scratch_.size() - hi);
    double W = 0.0;
    for (std::size_t k = lo; k < hi; ++k) W += scratch_[k].w;
    if (W <= 0.0) continue;
    // The kept neighbours' share of the step: c_k = (w_k / W) min(1 - exp(-k W dt), s), a convex
    // combination with at least 1 - s on one's own value.
    const double g = std::min(-std::expm1(-cfg_.gain * W * t.dt_s), s) / W;
    double dq = 0.0;
    for (std::size_t k = lo; k < hi; ++k) dq += g * scratch_[k].w * (scratch_[k].v - own);
    next[d] = own + dq;
  }
  q_ = next;
}

Vec3 EdgeFlowLaw::state() const {
  Vec3 q = q0_;
  for (const auto& [peer, o] : owned_) q -= o.entry.flow;
  for (const auto& [peer, c] : copies_) q += c.flow + c.predicted;
  return q;
}

std::vector<FlowEntry> EdgeFlowLaw::owned_flows() const {
  std::vector<FlowEntry> out;
  for (const auto& [peer, o] : owned_)
    if (o.entry.active || !o.settled || askers_.count(peer)) out.push_back(o.entry);
  // A restarted peer asks about an edge this agent never moved on: nothing, said explicitly.
  for (const AgentId peer : askers_)
    if (owns(peer) && !owned_.count(peer)) out.push_back({peer, Vec3::Zero(), 0.0, false});
  return out;
}

bool EdgeFlowLaw::shows(AgentId owner, const Copy& c) const {
  return c.linked || (c.seen && (c.announced || askers_.count(owner)));
}

std::vector<FlowEntry> EdgeFlowLaw::held_copies() const {
  std::vector<FlowEntry> out;
  for (const auto& [owner, c] : copies_)
    if (shows(owner, c)) out.push_back({owner, c.flow, 0.0, c.hearing});
  for (const AgentId owner : askers_) {
    if (owns(owner)) continue;
    const auto it = copies_.find(owner);
    if (it == copies_.end() || !shows(owner, it->second))
      out.push_back({owner, Vec3::Zero(), 0.0, false});
  }
  return out;
}

void EdgeFlowLaw::links_observed() {
  // The first message already says whom this agent links and hears (a new link forms only on a
  // current view), so that a fixed graph moves from the first tick on, as the Laplacian law does.
  for (const auto& [peer, w] : links_) {
    if (w <= 0.0) continue;
    if (!owns(peer)) {
      Copy& c = copies_[peer];
      c.linked = c.hearing = true;
    } else if (!owned_.count(peer) && (!recovering_ || answered_.count(peer))) {
      // A zero flow, settled: what the other end holds already. Not before a restarted agent
      // knows its flow on the edge: a zero announced then would overwrite the other end's copy.
      Owned& o = owned_[peer];
      o.entry = {peer, Vec3::Zero(), w, true};
      o.settled = true;
    }
  }
}

std::set<AgentId> EdgeFlowLaw::settling() const {
  std::set<AgentId> out;
  for (const auto& [peer, o] : owned_)
    if (!o.entry.active && !o.settled) out.insert(peer);
  for (const auto& [owner, c] : copies_)
    if (!c.linked && !c.quiet) out.insert(owner);
  return out;
}

std::vector<AgentId> EdgeFlowLaw::asking() const {
  return {unanswered_.begin(), unanswered_.end()};
}

namespace {
const FlowEntry* entry_for(const std::vector<FlowEntry>& entries, AgentId id) {
  for (const FlowEntry& e : entries)
    if (e.peer == id) return &e;
  return nullptr;
}
}  // namespace

bool EdgeFlowLaw::take_answer(const NeighborView& v) {
  if (owns(v.id)) {
    // Our flow on this edge, as the other end holds its copy: adopted before we move on it again.
    const FlowEntry* c = entry_for(v.copies, self_);
    if (!c) return false;
    if (!c->flow.isZero()) {
      Owned& o = owned_[v.id];
      o.entry = {v.id, c->flow, 0.0, false};
      o.settled = false;
      ++recovered_;
    }
  } else if (!entry_for(v.flows, self_)) {
    return false;  // the owner's flow arrives as a copy through integrate()
  }
  answered_.insert(v.id);
  return true;
}

void EdgeFlowLaw::recover(const std::vector<NeighborView>& neighbors) {
  recovering_ = true;
  unanswered_.clear();
  for (const NeighborView& v : neighbors)
    if (!answered_.count(v.id) && !take_answer(v)) unanswered_.insert(v.id);
}

int EdgeFlowLaw::messages_since(const Owned& o, std::uint64_t seq) {
  if (!o.heard) return 1;
  if (seq > o.heard_seq)
    return static_cast<int>(std::min<std::uint64_t>(seq - o.heard_seq, kMoveCredit));
  return seq == o.heard_seq ? 0 : 1;  // a smaller count: the other end restarted
}

void EdgeFlowLaw::integrate(const Tick& t) {
  const std::vector<NeighborView>& neighbors = t.neighbors;
  const std::vector<double>& coef = t.coef;
  const Vec3 q = state();  // every edge moves from the same snapshot of q_i (Jacobi)
  for (auto& [peer, o] : owned_) o.entry.active = false;
  for (auto& [peer, c] : copies_) {
    c.was_hearing = c.hearing;
    c.linked = c.hearing = false;
  }
  askers_.clear();
  unanswered_.clear();
  std::set<AgentId> heard;
  for (size_t k = 0; k < neighbors.size(); ++k) {
    const NeighborView& n = neighbors[k];
    for (const AgentId a : n.asking)
      if (a == self_) askers_.insert(n.id);
    const bool answered = !recovering_ || answered_.count(n.id) || take_answer(n);
    if (!answered) unanswered_.insert(n.id);
    if (owns(n.id)) {
      if (!answered) continue;  // nothing moves on this edge before its flow is known
      auto it = owned_.find(n.id);
      // The other end's copy says whether it hears this agent lately: without that, what moves
      // here might never be taken in there.
      const FlowEntry* copy = entry_for(n.copies, self_);
      if (coef[k] > 0.0) {
        const bool first = it == owned_.end();
        Owned& o = first ? owned_[n.id] : it->second;
        if (first) o.settled = true;  // a zero flow: what the other end holds already
        o.entry.peer = n.id;
        o.entry.weight = links_.count(n.id) ? links_.at(n.id) : 0.0;
        o.entry.active = true;  // announced while linked, moved on or not (the other end asks)
        // A move per message of the other end's (kMoveCredit): what the other end takes in when
        // it wakes from a stall is at most kMoveCredit steps, not one per tick it slept.
        o.credit = std::min(kMoveCredit, o.credit + messages_since(o, n.seq));
        o.heard = true;
        o.heard_seq = n.seq;
        if (copy && copy->active && o.credit > 0) {
          o.entry.flow += coef[k] * (q - n.q);
          o.settled = false;
          --o.credit;
        }
      } else if (it != owned_.end() && !askers_.count(n.id)) {
        // Settled once the other end shows the flow as it stands.
        if (copy && copy->flow == it->second.entry.flow) it->second.settled = true;
      } else if (it != owned_.end()) {
        it->second.settled = false;  // it restarted and asks: announce until it shows the copy
      }
    } else {
      heard.insert(n.id);
      // The neighbour owns the edge: a newer message replaces copy and prediction.
      const FlowEntry* e = entry_for(n.flows, self_);
      auto it = copies_.find(n.id);
      // An edge never linked, never moved on and not linked by its owner costs no entry.
      if (it == copies_.end() && coef[k] <= 0.0 && (!e || (e->flow.isZero() && !e->active)))
        continue;
      Copy& c = it != copies_.end() ? it->second : copies_[n.id];
      const bool fresh = !c.seen || n.seq != c.seq;  // a new message (or a restarted owner)
      if (fresh) {
        if (e) c.flow = e->flow;
        c.announced = e != nullptr;
        c.predicted.setZero();
        c.seq = n.seq;
        c.seen = true;
      }
      c.linked = coef[k] > 0.0;
      c.hearing = n.current;
      if (c.linked || (fresh && e)) {
        c.quiet = false;
      } else if (fresh) {
        c.quiet = true;
      }
      // The owner moves while it links this agent (its flow's active) and this agent's last
      // message said it heard the owner (the copy's active), once per message of this agent's:
      // predict on the same terms, a move a tick (one its credit withheld, the next copy undoes).
      if (c.linked && c.was_hearing && e && e->active) c.predicted += coef[k] * (n.q - q);
    }
  }
  // A silent owner's increments can no longer be confirmed: keep only its last copy.
  for (auto& [peer, c] : copies_) {
    if (!heard.count(peer)) c.predicted.setZero();
  }
}

}  // namespace qswarm
