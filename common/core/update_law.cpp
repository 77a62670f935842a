#include "common/core/update_law.hpp"

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
  return {};
}

std::string to_string(LawKind k) {
  switch (k) {
    case LawKind::kLaplacian:
      return "laplacian";
    case LawKind::kWmsr:
      return "w-msr";
    case LawKind::kEdgeFlow:
      break;
  }
  return "edge-flow";
}

LawKind parse_law_kind(const std::string& s) {
  if (s == "laplacian") return LawKind::kLaplacian;
  if (s == "edge-flow" || s == "edge_flow") return LawKind::kEdgeFlow;
  if (s == "w-msr" || s == "w_msr" || s == "wmsr") return LawKind::kWmsr;
  throw std::invalid_argument("update law '" + s + "': expected laplacian, edge-flow or w-msr");
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
  if (wmsr_f < 0 || wmsr_f > 64) {
    throw std::invalid_argument("law.wmsr_f = " + std::to_string(wmsr_f) +
                                ": expected 0 to 64 lying neighbours");
  }
  if (!std::isfinite(weight.scale) || weight.scale <= 0.0) {
    throw std::invalid_argument("weight.scale: expected a finite value > 0");
  }
}

UpdateLaw::UpdateLaw(AgentId self, const Vec3& q0, LawConfig cfg)
    : self_(self), q0_(q0), cfg_(std::move(cfg)), tracker_(self, cfg_.topology) {
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
  v.seq = ticks_;
  return v;
}

std::unique_ptr<UpdateLaw> make_law(AgentId self, const Vec3& q0, const LawConfig& cfg) {
  if (cfg.kind == LawKind::kLaplacian) return std::make_unique<LaplacianLaw>(self, q0, cfg);
  if (cfg.kind == LawKind::kWmsr) return std::make_unique<WmsrLaw>(self, q0, cfg);
  return std::make_unique<EdgeFlowLaw>(self, q0, cfg);
}

void LaplacianLaw::integrate(const Tick& t) {
  Vec3 dq = Vec3::Zero();
  for (size_t k = 0; k < t.neighbors.size(); ++k) dq -= t.coef[k] * (q_ - t.neighbors[k].q);
  q_ += dq;
}

void WmsrLaw::integrate(const Tick& t) {
  const auto F = static_cast<std::size_t>(cfg_.wmsr_f);
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
  for (const auto& [peer, f] : owned_) q -= f.flow;
  for (const auto& [peer, c] : copies_) q += c.flow + c.predicted;
  return q;
}

std::vector<FlowEntry> EdgeFlowLaw::owned_flows() const {
  std::vector<FlowEntry> out;
  out.reserve(owned_.size());
  for (const auto& [peer, f] : owned_) out.push_back(f);
  return out;
}

std::vector<FlowEntry> EdgeFlowLaw::held_copies() const {
  std::vector<FlowEntry> out;
  out.reserve(copies_.size());
  for (const auto& [owner, c] : copies_) {
    if (c.seen) out.push_back({owner, c.flow, 0.0, false});
  }
  return out;
}

void EdgeFlowLaw::adopt(const NeighborView& v) {
  if (!adopted_.insert(v.id).second) return;
  for (const FlowEntry& c : v.copies) {
    if (c.peer != self_) continue;
    FlowEntry& f = owned_[v.id];
    f.peer = v.id;
    f.flow = c.flow;
    ++recovered_;
  }
}

void EdgeFlowLaw::recover(const std::vector<NeighborView>& neighbors) {
  recovering_ = true;
  for (const NeighborView& v : neighbors)
    if (owns(v.id)) adopt(v);
}

void EdgeFlowLaw::integrate(const Tick& t) {
  const std::vector<NeighborView>& neighbors = t.neighbors;
  const std::vector<double>& coef = t.coef;
  const Vec3 q = state();  // every edge moves from the same snapshot of q_i (Jacobi)
  for (auto& [peer, f] : owned_) f.active = false;
  std::map<AgentId, bool> heard;
  for (size_t k = 0; k < neighbors.size(); ++k) {
    const NeighborView& n = neighbors[k];
    if (owns(n.id)) {
      if (recovering_) adopt(n);  // before any increment on this edge in this life
      if (coef[k] <= 0.0) continue;
      FlowEntry& f = owned_[n.id];
      f.peer = n.id;
      f.flow += coef[k] * (q - n.q);
      f.weight = links_.count(n.id) ? links_.at(n.id) : 0.0;
      f.active = true;
    } else {
      heard[n.id] = true;
      // The neighbour owns the edge: a newer message replaces copy and prediction.
      Copy& c = copies_[n.id];
      if (!c.seen || n.seq != c.seq) {  // a new message (or a restarted owner: seq from 1)
        for (const FlowEntry& e : n.flows) {
          if (e.peer == self_) c.flow = e.flow;
        }
        c.predicted.setZero();
        c.seq = n.seq;
        c.seen = true;
      }
      if (coef[k] > 0.0) c.predicted += coef[k] * (n.q - q);
    }
  }
  // A silent owner's increments can no longer be confirmed: keep only its last copy.
  for (auto& [peer, c] : copies_) {
    if (!heard.count(peer)) c.predicted.setZero();
  }
}

}  // namespace qswarm
