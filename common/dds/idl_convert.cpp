#include "common/dds/idl_convert.hpp"

#include <stdexcept>
#include <string>

namespace qswarm {
namespace {

Vec3 vec(const std::array<double, 3>& a) { return Vec3(a[0], a[1], a[2]); }
std::array<double, 3> arr(const Vec3& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace

static_assert(kMaxBarrierBytes == 64, "idl/swarm_state.idl bounds the barrier bitsets at 64");
static_assert(kMaxLawPayload == 64, "idl/swarm_state.idl bounds a law's payload at 64");

void to_idl(const StateMessage& m, qswarm_msgs::AgentState& s) {
  // The wire carries every entry or the sample is not sent: a silently cut flow list would break
  // edge-flow's conservation. The scenario refuses swarms larger than kMaxSwarmAgents.
  for (const std::size_t n : {m.links.size(), m.initial_links.size(), m.view.flows.size(),
                              m.view.copies.size(), m.view.asking.size()}) {
    if (n > kMaxWireEntries) {
      throw std::length_error("state sample of agent " + std::to_string(m.view.id) + " has " +
                              std::to_string(n) + " entries in a list the wire bounds at " +
                              std::to_string(kMaxWireEntries));
    }
  }
  s.id(m.view.id);
  s.seq(m.seq);
  s.view_seq(m.view.seq);
  s.stamp_s(m.stamp_s);
  s.wall_ns(m.wall_ns);
  s.incarnation(m.incarnation);
  s.run_id(m.run_id);
  s.mode(static_cast<uint8_t>(m.mode));
  s.phase(static_cast<std::uint8_t>(m.phase));
  s.consensus(arr(m.view.q));
  s.initial(arr(m.view.q0));
  s.total_weight(m.view.total_weight);
  s.position(arr(m.p_W));
  s.velocity(arr(m.v_W));
  s.orientation({m.q_WB.w(), m.q_WB.x(), m.q_WB.y(), m.q_WB.z()});
  s.rotors({m.rotors_radps[0], m.rotors_radps[1], m.rotors_radps[2], m.rotors_radps[3]});
  s.received(m.received);
  s.dropped(m.dropped);
  s.overruns(m.overruns);
  s.trimmed(m.trimmed);
  s.faults().loss(m.faults.loss);
  s.faults().burst(m.faults.burst);
  s.faults().cut(m.faults.cut);
  s.faults().partition(m.faults.partition);
  s.faults().delayed(m.faults.delayed);
  if (m.strangers.size() > kMaxStrangers)
    throw std::length_error("a sample reports at most " + std::to_string(kMaxStrangers) +
                            " strangers");
  s.strangers(m.strangers);
  if (m.suspects.size() > kMaxSuspects)
    throw std::length_error("a sample reports at most " + std::to_string(kMaxSuspects) +
                            " suspects");
  s.suspects().clear();
  for (const Suspect& x : m.suspects) {
    qswarm_msgs::Suspect e;
    e.id(x.id);
    e.kinds(x.kinds);
    s.suspects().push_back(e);
  }
  const auto put_links = [](const std::vector<std::pair<AgentId, double>>& in,
                            std::vector<qswarm_msgs::LinkEntry>& out) {
    out.clear();
    for (const auto& [peer, w] : in) {
      qswarm_msgs::LinkEntry e;
      e.peer(peer);
      e.weight(w);
      out.push_back(e);
    }
  };
  put_links(m.links, s.links());
  put_links(m.initial_links, s.initial_links());
  s.flows().clear();
  for (const FlowEntry& f : m.view.flows) {
    qswarm_msgs::FlowEntry e;
    e.peer(f.peer);
    e.flow(arr(f.flow));
    e.weight(f.weight);
    e.active(f.active);
    s.flows().push_back(e);
  }
  s.copies().clear();
  for (const FlowEntry& f : m.view.copies) {
    qswarm_msgs::FlowEntry e;
    e.peer(f.peer);
    e.flow(arr(f.flow));
    e.active(f.active);  // the holder heard the owner lately: the owner may move on the edge
    s.copies().push_back(e);
  }
  s.asking(m.view.asking);
  if (m.view.payload.size() > kMaxLawPayload)
    throw std::length_error("a law's payload is at most " + std::to_string(kMaxLawPayload) +
                            " values");
  s.law(m.view.law);
  s.payload(m.view.payload);
  if (m.barrier_known.size() > kMaxBarrierBytes || m.barrier_ready.size() > kMaxBarrierBytes)
    throw std::length_error("a start barrier bitset is at most " +
                            std::to_string(kMaxBarrierBytes) + " bytes");
  s.barrier_known(m.barrier_known);
  s.barrier_ready(m.barrier_ready);
  s.barrier_ready_at_s(m.barrier_ready_at_s);
  if (m.host.size() > kMaxHostBytes)
    throw std::length_error("a host is at most " + std::to_string(kMaxHostBytes) + " bytes");
  s.host(m.host);
}

StateMessage from_idl(const qswarm_msgs::AgentState& s) {
  StateMessage m;
  from_idl(s, m);
  return m;
}

void from_idl(const qswarm_msgs::AgentState& s, StateMessage& m) {
  m.view.id = s.id();
  m.seq = s.seq();
  m.view.seq = s.view_seq();
  m.stamp_s = s.stamp_s();
  m.wall_ns = s.wall_ns();
  m.incarnation = s.incarnation();
  m.run_id = s.run_id();
  m.mode = static_cast<PoseKind>(s.mode());
  m.phase = static_cast<Phase>(s.phase());
  m.view.q = vec(s.consensus());
  m.view.q0 = vec(s.initial());
  m.view.total_weight = s.total_weight();
  m.p_W = vec(s.position());
  m.v_W = vec(s.velocity());
  m.q_WB = Eigen::Quaterniond(s.orientation()[0], s.orientation()[1], s.orientation()[2],
                              s.orientation()[3]);
  m.rotors_radps = RotorSpeeds(s.rotors()[0], s.rotors()[1], s.rotors()[2], s.rotors()[3]);
  m.received = s.received();
  m.dropped = s.dropped();
  m.overruns = s.overruns();
  m.trimmed = s.trimmed();
  m.faults = {s.faults().loss(), s.faults().burst(), s.faults().cut(), s.faults().partition(),
              s.faults().delayed()};
  m.strangers.assign(s.strangers().begin(), s.strangers().end());
  m.suspects.clear();
  for (const auto& e : s.suspects()) m.suspects.push_back({e.id(), e.kinds()});
  m.links.clear();
  for (const auto& e : s.links()) m.links.emplace_back(e.peer(), e.weight());
  m.initial_links.clear();
  for (const auto& e : s.initial_links()) m.initial_links.emplace_back(e.peer(), e.weight());
  m.view.copies.clear();
  for (const auto& e : s.copies())
    m.view.copies.push_back({e.peer(), vec(e.flow()), 0.0, e.active()});
  m.view.flows.clear();
  for (const auto& e : s.flows())
    m.view.flows.push_back({e.peer(), vec(e.flow()), e.weight(), e.active()});
  m.view.asking.assign(s.asking().begin(), s.asking().end());
  m.view.law = s.law();
  m.view.payload.assign(s.payload().begin(), s.payload().end());
  m.barrier_known.assign(s.barrier_known().begin(), s.barrier_known().end());
  m.barrier_ready.assign(s.barrier_ready().begin(), s.barrier_ready().end());
  m.barrier_ready_at_s = s.barrier_ready_at_s();
  m.host = s.host();
  m.view.link_distance_m = NeighborView{}.link_distance_m;  // not on the wire
  m.view.current = NeighborView{}.current;
}

void to_idl(const IdClaim& c, qswarm_msgs::IdClaim& s) {
  s.nonce(c.nonce);
  s.seq(c.seq);
  s.run_id(c.run_id);
  s.expected(c.expected);
  s.id(c.id);
  s.stage(c.stage);
  s.flying_s(c.flying_s);
}

IdClaim from_idl(const qswarm_msgs::IdClaim& s) {
  IdClaim c;
  c.nonce = s.nonce();
  c.seq = s.seq();
  c.run_id = s.run_id();
  c.expected = s.expected();
  c.id = s.id();
  c.stage = s.stage();
  c.flying_s = s.flying_s();
  return c;
}

}  // namespace qswarm
