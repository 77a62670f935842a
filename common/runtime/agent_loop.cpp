#include "common/runtime/agent_loop.hpp"

#include "common/runtime/neighbourhood.hpp"

#include <algorithm>
#include <cstdio>
#include <iterator>

namespace qswarm {
namespace {

// Whether this process starts on the swarm's clock instead of passing the barrier, and when.
std::optional<double> join_time(const RunConfig& rc, AgentId id, const AgentLoopOptions& o) {
  if (o.join_at_s >= 0.0) return o.join_at_s;
  return rc.faults.late_join_at(id);
}

// Wall seconds per consensus tick.
double tick_wall_s(const RunConfig& rc, const AgentLoopOptions& o) {
  return rc.agent.steps_per_tick() / (rc.agent.physics_hz * o.time_scale);
}

LifecycleConfig lifecycle_config(const RunConfig& rc, AgentId id, const AgentLoopOptions& o,
                                 double tick_origin_s) {
  LifecycleConfig c;
  c.join_at_s = join_time(rc, id, o);
  if (!c.join_at_s) {
    c.barrier_peers = start_peers(rc, id);
    c.min_matched_readers = static_cast<int>(c.barrier_peers.size());
    c.wait_recorder = o.wait_supervisor;
    // Late joiners never reach a barrier: their bits could never turn ready.
    const std::set<AgentId> late = rc.faults.late_joiners();
    for (const AgentId a : rc.ids())
      if (!late.count(a)) c.roster.push_back(a);
    c.self = id;
    c.shared_origin_s = tick_origin_s;
  }
  c.time_scale = o.time_scale;
  c.duration_s = rc.judge.duration_s;
  const RunPlan plan = plan_at(rc, o.time_scale);  // its wall periods follow the time scale
  c.start_timeout_s = o.start_timeout_s >= 0.0 ? o.start_timeout_s : plan.start_timeout_s;
  c.join_timeout_s = c.start_timeout_s + (plan.join_timeout_s - plan.start_timeout_s);
  c.announce_period_s = plan.barrier_announce_period_s;
  c.waiting_period_s = plan.barrier_waiting_period_s;
  c.tick_wall_s = tick_wall_s(rc, o);
  // The lifecycle's grid lies at multiples of the period from tick_origin_s: a later phase moves
  // that origin back.
  c.tick_origin_s = tick_origin_s - o.tick_phase * c.tick_wall_s;
  c.max_wall_s = o.max_wall_s >= 0.0 ? o.max_wall_s : plan.agent_wall_limit_s;
  c.kill_at_s = rc.faults.kills_of(id);
  return c;
}

}  // namespace

namespace {

AgentParams params_for(const RunConfig& rc, AgentId id, const AgentLoopOptions& o) {
  const AgentSpec* spec = rc.spec(id);
  if (!spec) throw std::invalid_argument("agent " + std::to_string(id) + " is not in the run");
  AgentParams p{*spec, rc.agent, {}};
  p.start.incarnation = o.incarnation;
  p.start.run_id = rc.transport.run_id;
  p.start.expected_peers = start_peers(rc, id).size();
  p.start.record_every = rc.plan.record_every;
  p.start.spread_records = rc.plan.spread_records;
  p.start.links_to_neighbours = rc.plan.delivery == Delivery::kReach;
  p.start.host = o.host;
  if (join_time(rc, id, o)) {
    p.start.expected_peers = 0;  // joins a running swarm: no first-tick wait
    p.start.recover_flows = o.restarted;
  }
  return p;
}

}  // namespace

AgentLoop::AgentLoop(const RunConfig& rc, AgentId id, const AgentLoopOptions& opts,
                     NeighborBus& transport, Clock& clock)
    : id_(id),
      is_agent_([ids = rc.ids()](AgentId a) { return ids.count(a) > 0; }),
      clock_(clock),
      transport_(transport),
      faulty_(transport, LinkFaults(rc.faults, id, rc.seed), id),
      runtime_(params_for(rc, id, opts), faulty_),
      life_(lifecycle_config(rc, id, opts, clock.shared_origin_s()), clock.now_s()),
      neighbourhood_(rc, id),
      record_period_wall_s_(rc.plan.record_every * tick_wall_s(rc, opts)),
      last_announce_record_s_(clock.now_s()) {
  runtime_.set_wall_clock(&clock_);
  update_interest();
}

void AgentLoop::update_interest() {
  std::set<AgentId> linked;
  for (const auto& [peer, w] : runtime_.law().links()) linked.insert(peer);
  Neighbourhood::Settling settling;
  for (const AgentId peer : runtime_.law().settling()) settling[peer] = runtime_.hears(peer);
  Interest in = neighbourhood_.update(runtime_.position(), runtime_.consensus(), linked, settling);
  if (interest_told_ && in == interest_) return;
  interest_ = std::move(in);
  if (interest_told_) ++interest_changes_;
  interest_told_ = true;
  transport_.set_interest(interest_);
}

std::uint64_t AgentLoop::ticks() const { return life_.pacer() ? life_.pacer()->ticks() : 0; }
std::uint64_t AgentLoop::overruns() const { return life_.pacer() ? life_.pacer()->overruns() : 0; }
double AgentLoop::running_since_s() const {
  return life_.pacer() ? life_.pacer()->start_s() : -1.0;
}

AgentLoop::Poll AgentLoop::poll() {
  Poll r;
  const double now = clock_.now_s();
  std::vector<PeerStatus> peers;
  if (life_.phase() != LifePhase::kRunning) {
    // The barrier and the join wait read the raw transport: faults apply to the run, which
    // starts once everyone is up.
    // Only the run's own agents count: a stranger's stamp must not start a late joiner early.
    // Read in place: a large swarm's barrier polls often and copies only what the barrier reads.
    transport_.for_each_latest(id_, [&](const StateMessage& m) {
      if (is_agent_(m.view.id))
        peers.push_back({m.view.id, m.phase, m.stamp_s, m.barrier_known, m.barrier_ready,
                         m.barrier_ready_at_s});
    });
  }
  const LifecycleStep s = life_.step(now, peers, transport_.matched_readers(), runtime_.time_s(),
                                     transport_.recorder_confirmed());
  if (!s.warning.empty()) r.notes.push_back({true, s.warning});
  if (!s.progress.empty()) r.notes.push_back({false, s.progress});
  if (s.swarm_time_s >= 0.0) faulty_.set_time(s.swarm_time_s);
  // The barrier's announcements come slower than ticks: one goes to the recorder too whenever the
  // last record is a record period old, so that the supervisor keeps hearing a waiting agent and
  // can confirm hearing it (the start waits for that), as every k-th tick does in flight.
  if (s.announce) {
    runtime_.set_barrier(life_.known_bits(), life_.ready_bits(), life_.ready_at_s());
    if (runtime_.publish(*s.announce, now - last_announce_record_s_ >= record_period_wall_s_))
      last_announce_record_s_ = now;
  }
  if (s.start) {
    if (s.late)
      runtime_.join_running(s.start_time_s);
    else
      runtime_.set_start_time(s.start_time_s);
    char buf[160];
    std::snprintf(buf, sizeof buf, "%s at swarm time %.3f s after %.2f s of discovery",
                  runtime_.params().start.recover_flows ? "restarting"
                  : runtime_.params().start.expected_peers == 0 && s.start_time_s > 0.0
                      ? "joining late"
                      : "running",
                  s.start_time_s, life_.discovery_s());
    r.notes.push_back({false, buf});
  }
  r.kill = s.kill;
  r.done = s.stop;
  r.wake_at_s = s.wake_at_s;
  if (s.ticks > 0) {
    const BusCounters c = transport_.counters();
    runtime_.set_counters(c.received, c.dropped + c.stale, overruns());
    runtime_.set_fault_counters(faulty_.fault_counters());
    runtime_.set_strangers(transport_.strangers());
    runtime_.set_suspects(transport_.suspects());
    faulty_.set_time(runtime_.time_s());
    for (int i = 0; i < runtime_.steps_per_tick(); ++i, ++physics_steps_) {
      for (const AgentEvent& e : runtime_.step()) {
        char buf[120];
        std::snprintf(
            buf, sizeof buf, "t=%.3f s: neighbour %u %s", e.t_s, e.peer,
            e.kind == AgentEvent::kNeighborHeard ? "heard" : "lost (silent past timeout)");
        r.notes.push_back({false, buf});
      }
    }
    update_interest();  // it may have moved into another cell or gained a link
  }
  return r;
}

void AgentLoop::stop() {
  life_.stop();
  runtime_.publish(Phase::kStopping);
}

}  // namespace qswarm
