#include "common/sim/in_process_swarm.hpp"

#include <algorithm>
#include <cstdio>
#include <limits>

namespace qswarm {

InProcessSwarm::InProcessSwarm(RunConfig rc, double time_scale)
    : rc_(std::move(rc)), time_scale_(time_scale) {
  for (const AgentSpec& a : rc_.agents) spawn(a.id, slots_[a.id]);
}

InProcessSwarm::~InProcessSwarm() {
  // Each loop unregisters from its endpoint before the endpoint goes.
  for (auto& [id, s] : slots_) s.loop.reset();
}

void InProcessSwarm::spawn(AgentId id, Slot& slot) {
  AgentLoopOptions o;
  o.time_scale = time_scale_;
  o.incarnation = slot.life + 1;  // a respawn is a newer life
  if (slot.life > 0) {
    // Like the launcher: the n-th respawn joins at the n-th planned restart and recovers flows.
    o.join_at_s = rc_.faults.restarts_of(id).at(static_cast<std::size_t>(slot.life - 1));
    o.restarted = true;
  }
  slot.loop.reset();
  slot.bus = std::make_unique<InMemoryBus>(net_);  // a new process has a new transport
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
      const bool restarts = s.life <= static_cast<int>(rc_.faults.restarts_of(id).size());
      s.loop.reset();  // dies silently, like SIGKILL
      s.bus.reset();
      if (restarts) {
        spawn(id, s);
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
  double next = std::numeric_limits<double>::infinity();
  for (const auto& [id, s] : slots_)
    if (s.loop && !s.finished) next = std::min(next, s.wake_at_s);
  if (next < std::numeric_limits<double>::infinity()) clock_.set(next);
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
