#include "common/runtime/agent_runtime.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace qswarm {
AgentRuntime::AgentRuntime(AgentParams p, NeighborBus& bus)
    : p_(std::move(p)),
      bus_(bus),
      law_(make_law(p_.spec.id, p_.spec.position_W - p_.spec.offset_W, p_.config.law)),
      plant_spec_(p_.config.plant_spec()),
      reference_(p_.spec.position_W, p_.config.reference_speed_mps,
                 p_.config.reference_accel_mps2) {
  if (!(p_.config.physics_hz > 0.0) || !(p_.config.consensus_hz > 0.0) ||
      p_.config.consensus_hz > p_.config.physics_hz) {
    throw std::invalid_argument("rates: need 0 < consensus_hz <= physics_hz");
  }
  p_.config.airframe.validate();
  p_.config.gains.validate();
  steps_per_tick_ = p_.config.steps_per_tick();
  if (p_.config.law.topology.policy == TopologyPolicy::kFixed) {
    listen_to_ = listed_peers(p_.config.law.topology, p_.spec.id);
  }
  if (p_.config.avoidance.enabled) p_.config.avoidance.validate();
  plant_ = make_plant(
      p_.config.plant,
      {p_.spec.id, p_.spec.position_W, p_.spec.yaw_rad, p_.config.airframe, p_.config.gains, {}});
  plant_->aim(goal());
}

void AgentRuntime::set_start_time(double t_s) {
  if (steps_ != 0) throw std::logic_error("set_start_time after the first step");
  p_.start.start_time_s = t_s;
}

void AgentRuntime::join_running(double t_s) {
  set_start_time(t_s);
  p_.start.expected_peers = 0;
  p_.start.recover_flows = true;
}

bool AgentRuntime::publish(Phase phase, bool record) {
  StateMessage m;
  m.view = law_->message();
  const std::uint64_t k = p_.start.record_every;
  // The first tick's sample of an agent started at the barrier is sent before its law linked
  // anyone: with records sparser than ticks, it goes to the neighbours only.
  const bool first_tick = phase == Phase::kRunning && !published_running_;
  if (first_tick) {
    // Which of its ticks an agent records does not depend on how many announcements it made at
    // its start barrier: the k-th (all agents the same) or one set by its id (spread_records).
    published_running_ = true;
    const std::uint64_t first_record_tick = p_.start.spread_records ? 1 + p_.spec.id % k : k;
    seq_ += (k - (seq_ + first_record_tick) % k) % k;
  }
  m.seq = ++seq_;
  m.stamp_s = time_s();
  m.mode = plant_spec_.oriented ? PoseKind::kOriented : PoseKind::kPosition;
  m.phase = phase;
  m.p_W = plant_->position();
  m.v_W = plant_->velocity();
  m.q_WB = plant_->attitude();
  m.rotors_radps = plant_->rotors();
  const auto add_links = [&] {
    for (const auto& [peer, w] : law_->links()) m.links.emplace_back(peer, w);
  };
  if (p_.start.links_to_neighbours) add_links();
  m.incarnation = p_.start.incarnation;
  m.run_id = p_.start.run_id;
  m.received = received_;
  m.dropped = dropped_;
  m.overruns = overruns_;
  m.trimmed = law_->trimmed_total();
  m.faults = faults_;
  m.strangers = strangers_;
  m.suspects = suspects_;
  if (phase == Phase::kWaiting || phase == Phase::kReady) {
    m.barrier_known = barrier_known_;
    m.barrier_ready = barrier_ready_;
    m.barrier_ready_at_s = barrier_ready_at_s_;
  }
  m.wall_ns = wall_now_ns();
  bus_.publish(m);
  // The recorder gets every k-th sample, and the goodbye (a departure it sees at once), with the
  // links and the initial links.
  if (record || (m.seq % k == 0 && !(first_tick && k > 1)) || phase == Phase::kStopping) {
    if (!p_.start.links_to_neighbours) add_links();
    m.initial_links = initial_links_;
    m.host = p_.start.host;
    m.wall_ns = wall_now_ns();  // handed over after the state sample
    bus_.record(m);
    return true;
  }
  return false;
}

void AgentRuntime::set_strangers(const std::set<AgentId>& ids) {
  strangers_.assign(ids.begin(), ids.end());
  if (strangers_.size() > kMaxStrangers) strangers_.resize(kMaxStrangers);
}

void AgentRuntime::set_suspects(const std::map<AgentId, std::uint8_t>& suspects) {
  suspects_.clear();
  for (const auto& [id, kinds] : suspects) {
    if (suspects_.size() == kMaxSuspects) break;
    suspects_.push_back({id, kinds});
  }
}

bool AgentRuntime::current(const Peer& p, double t) const {
  const double tick_s = static_cast<double>(steps_per_tick_) / p_.config.physics_hz;
  return t - p.last_new_s <= std::max(2.0 * tick_s, 0.25 * p_.config.neighbor_timeout_s) + 1e-9;
}

bool AgentRuntime::hears(AgentId peer) const {
  const auto it = peers_.find(peer);
  return it != peers_.end() && current(it->second, time_s());
}

void AgentRuntime::consensus_tick(std::vector<AgentEvent>& events) {
  const double t = time_s();
  std::vector<NeighborView>& views = views_;
  std::size_t n_views = 0;
  // Under the bus's lock: read each message in place, and copy only its view, into the storage
  // this tick's element already has.
  bus_.for_each_latest(p_.spec.id, [&](const StateMessage& m) {
    const AgentId peer = m.view.id;
    if (peer == p_.spec.id) return;
    Peer& st = peers_[peer];
    const bool fresh = m.incarnation != st.incarnation || m.seq != st.seq;
    if (fresh) {
      st.seq = m.seq;
      st.incarnation = m.incarnation;
      st.last_new_s = t;
      st.phase = m.phase;
      st.p_W = m.p_W;
      st.v_W = m.v_W;
      // A running sample's position is for its stamp on the swarm's clock; a waiting agent's is
      // for now (it is not moving, and its stamp is not yet on the swarm's clock).
      st.at_s = m.phase == Phase::kRunning ? m.stamp_s : t;
    }
    if (m.phase != Phase::kRunning) return;
    if (!listen_to_.empty() && !listen_to_.count(peer)) return;  // explicit graph: not a neighbour
    if (fresh && live_.insert(peer).second) events.push_back({AgentEvent::kNeighborHeard, peer, t});
    if (t - st.last_new_s > p_.config.neighbor_timeout_s) {
      if (live_.erase(peer)) events.push_back({AgentEvent::kNeighborLost, peer, t});
      return;
    }
    if (n_views == views.size()) views.emplace_back();
    NeighborView& v = views[n_views++];
    v = m.view;
    v.current = current(st, t);
    // Radio range: the physical distance as this agent sees it (its own position, the
    // neighbour's last sample).
    if (p_.config.law.topology.policy == TopologyPolicy::kRange)
      v.link_distance_m = (position() - m.p_W).norm();
  });
  views.resize(n_views);
  if (!started_) {
    if (views.size() < p_.start.expected_peers &&
        t < p_.start.start_time_s + p_.start.start_grace_s) {
      publish(Phase::kRunning);  // running, but the law waits for the whole initial graph
      return;
    }
    if (p_.start.recover_flows) law_->recover(views);
    law_->observe(views);
    plant_->aim(goal());
    for (const auto& [peer, w] : law_->links()) initial_links_.emplace_back(peer, w);
    started_ = true;
    law_start_s_ = t;
  } else {
    law_->step(static_cast<double>(steps_per_tick_) / p_.config.physics_hz, views);
    plant_->aim(goal());
  }
  publish(Phase::kRunning);
}

void AgentRuntime::physics(double dt) {
  if (!plant_spec_.follows_reference) return;
  // The reference moves toward the law's goal within speed and acceleration limits so that it
  // stays flyable, and the plant's controller tracks it.
  obstacles_.clear();
  if (p_.config.avoidance.enabled) {
    // Every agent heard within the neighbour timeout, whatever the graph: a radio hears everyone
    // near. A stopping agent is gone.
    const double t = time_s();
    for (const auto& [peer, h] : peers_) {
      if (h.phase == Phase::kStopping || t - h.last_new_s > p_.config.neighbor_timeout_s) continue;
      obstacles_.push_back({peer, project_position(h.p_W, h.v_W, t - h.at_s)});
    }
  }
  plant_->step(
      reference_.step(goal(), dt, p_.spec.id, plant_->position(), obstacles_, p_.config.avoidance),
      dt);
  // A plant that diverged would send samples every gate drops: the agent would fall silent with
  // no word why. It ends here instead, naming its plant (the process exits 1).
  if (!plant_->position().allFinite() || !plant_->velocity().allFinite())
    throw std::runtime_error("plant " + plant_spec_.name + " of agent " +
                             std::to_string(p_.spec.id) +
                             ": its state is not finite at t = " + std::to_string(time_s()) + " s");
}

std::vector<AgentEvent> AgentRuntime::step() {
  std::vector<AgentEvent> events;
  if (steps_ % static_cast<std::uint64_t>(steps_per_tick_) == 0) consensus_tick(events);
  physics(1.0 / p_.config.physics_hz);
  ++steps_;
  return events;
}

}  // namespace qswarm
