#include "common/sim/in_process_swarm.hpp"

#include <algorithm>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace qswarm {

namespace {
// The run planned for one process on this host at the swarm's time scale.
RunConfig planned(RunConfig rc, double time_scale) {
  rc.plan = plan_at(rc, time_scale);
  return rc;
}
}  // namespace

InProcessSwarm::InProcessSwarm(RunConfig rc, double time_scale, RunDir record_in)
    : rc_(planned(std::move(rc), time_scale)), time_scale_(time_scale), restarts_(rc_.faults) {
  if (!record_in.empty()) {
    supervisor_bus_ = std::make_unique<InMemoryBus>(net_, InMemoryBus::Role::kRecorder,
                                                    expected_law(rc_.agent.law.law));
    SupervisorOptions o;
    o.time_scale = time_scale_;
    supervisor_ =
        std::make_unique<SupervisorLoop>(rc_, std::move(record_in), o, *supervisor_bus_, clock_);
  }
  for (const AgentSpec& a : rc_.agents) spawn(a.id, slots_[a.id], std::nullopt);
}

InProcessSwarm::~InProcessSwarm() {
  // Each loop unregisters from its endpoint before the endpoint goes.
  for (auto& [id, s] : slots_) s.loop.reset();
  supervisor_.reset();
}

void InProcessSwarm::spawn(AgentId id, Slot& slot, std::optional<double> join_at_s) {
  AgentLoopOptions o;
  o.time_scale = time_scale_;
  o.incarnation = slot.life + 1;  // a respawn is a newer life
  if (join_at_s) {
    // Like the launcher: a new life joins at its planned restart and recovers its flows.
    o.join_at_s = *join_at_s;
    o.restarted = true;
  }
  slot.loop.reset();
  // A new process has a new transport.
  slot.bus = std::make_unique<InMemoryBus>(net_, InMemoryBus::Role::kAgent,
                                           expected_law(rc_.agent.law.law));
  slot.loop = std::make_unique<AgentLoop>(rc_, id, o, *slot.bus, clock_);
  slot.wake_at_s = clock_.now_s();
}

void InProcessSwarm::note(AgentId id, const std::string& text) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f ", clock_.now_s());
  log_.push_back(buf + std::to_string(id) + " " + text);
}

void InProcessSwarm::step() {
  const double now = clock_.now_s();
  for (auto& [id, s] : slots_) {
    if (!s.loop || s.finished || s.wake_at_s > now) continue;
    const AgentLoop::Poll p = s.loop->poll();
    for (const AgentLoop::Note& n : p.notes) note(id, n.text);
    if (p.kill) {
      note(id, "planned kill");
      ++s.life;
      s.loop.reset();  // dies silently, like SIGKILL
      s.bus.reset();
      if (const std::optional<double> at = restarts_.after_planned_kill(id)) {
        spawn(id, s, at);
        note(id, "respawned");
      }
      continue;
    }
    if (p.done) {
      s.loop->stop();
      s.finished = true;
      continue;
    }
    s.wake_at_s = p.wake_at_s;
  }
  net_.deliver();
  if (supervisor_ && !end_reason_ && supervisor_wake_s_ <= now) {
    const SupervisorLoop::Poll p = supervisor_->poll(false);
    if (p.end_reason) end_reason_ = p.end_reason;
    supervisor_wake_s_ = p.wake_at_s;
  }
  double next = std::numeric_limits<double>::infinity();
  for (const auto& [id, s] : slots_)
    if (s.loop && !s.finished) next = std::min(next, s.wake_at_s);
  if (supervisor_ && !end_reason_) next = std::min(next, supervisor_wake_s_);
  if (next < std::numeric_limits<double>::infinity()) clock_.set(next);
}

void InProcessSwarm::crash(AgentId id) {
  Slot& s = slots_.at(id);
  note(id, "crashed");
  s.loop.reset();
  s.bus.reset();
}

void InProcessSwarm::add_liar(const Liar& liar) {
  if (!slots_.count(liar.id)) throw std::invalid_argument("add_liar: the liar is no agent");
  liars_.push_back(liar);
  // A point agent's position is its consensus state (its slot about it): a consistent liar says
  // both. (Each liar's own offset: one rewrite serves them all.)
  const bool says_position = !rc_.agent.plant_spec().follows_reference;
  net_.set_rewrite(
      [this, says_position](const InMemoryBus& from, const InMemoryBus& to, StateMessage& m) {
        const auto lying = std::find_if(liars_.begin(), liars_.end(), [&](const Liar& l) {
          return slots_.at(l.id).bus.get() == &from;
        });
        if (lying == liars_.end()) return;
        AgentId to_id = 0;  // the recorder
        for (const auto& [id, s] : slots_)
          if (s.bus.get() == &to) to_id = id;
        m.view.q = lying->claim(to_id, m.view.q0, m.stamp_s);
        if (says_position) m.p_W = m.view.q + rc_.spec(lying->id)->offset_W;
      });
}

std::string InProcessSwarm::run_recorded(double max_wall_s) {
  if (!supervisor_) throw std::logic_error("run_recorded: this swarm has no run directory");
  run_until([this] { return end_reason_.has_value(); }, max_wall_s);
  std::string reason = end_reason_.value_or("interrupted");
  // Like the launcher: the supervisor first, so it keeps the agents' last states; then the agents
  // say they stop.
  const std::string text = supervisor_->finish(reason);
  note(0, "supervisor: " + reason);
  for (auto& [id, s] : slots_)
    if (s.loop && !s.finished) {
      s.loop->stop();
      s.finished = true;
    }
  net_.deliver();
  return reason;
}

void InProcessSwarm::run_until_wall(double wall_s) {
  run_until([] { return false; }, wall_s);
}

bool InProcessSwarm::run_until(const std::function<bool()>& pred, double max_wall_s) {
  while (clock_.now_s() < max_wall_s) {
    if (pred()) return true;
    step();
    bool any = false;
    for (const auto& [id, s] : slots_) any |= s.loop && !s.finished;
    if (!any) break;
  }
  return pred();
}

const AgentLoop* InProcessSwarm::agent(AgentId id) const {
  const auto it = slots_.find(id);
  return it == slots_.end() ? nullptr : it->second.loop.get();
}

Positions InProcessSwarm::running_states() const {
  Positions q;
  for (const auto& [id, s] : slots_)
    if (s.loop && s.loop->phase() == LifePhase::kRunning)
      q.push_back(s.loop->runtime().consensus());
  return q;
}

double InProcessSwarm::disagreement_running() const {
  const Positions q = running_states();
  return q.empty() ? 0.0 : disagreement(q);
}

}  // namespace qswarm
