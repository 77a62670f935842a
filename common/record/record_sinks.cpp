#include "common/record/record_sinks.hpp"

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl.h>

#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "common/scenario/proto_util.hpp"

namespace qswarm {
namespace {

// CSV field: quoted, inner quotes doubled (details and names come from people and the network).
std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"') out += '"';
    out += (c == '\n' || c == '\r') ? ' ' : c;
  }
  return out + '"';
}

}  // namespace

RecordSinks::RecordSinks(const RunDir& dir, SceneSettings scene)
    : dir_(dir), mcap_(std::move(scene)) {
  telemetry_.open(dir_.telemetry());
  graph_.open(dir_.graph());
  events_.open(dir_.events());
  records_.open(dir_.records(), std::ios::binary);
  if (!telemetry_ || !graph_ || !events_ || !records_) {
    throw std::runtime_error("cannot write the run directory " + dir_.str());
  }
  telemetry_ << "stamp_s,id,seq,phase,mode,qx,qy,qz,px,py,pz,vx,vy,vz,qw,qxr,qyr,qzr,w1,w2,w3,w4,"
                "total_weight,links,age_ms\n";
  graph_ << "t_s,agents,edges,lambda2,components,disagreement_m,mean_drift_m,min_separation_m,"
            "spread_m,edge_list,min_degree,robust,trimmed_disagreement_m\n";
  events_ << "t_s,kind,agent,detail\n";
  telemetry_ << std::setprecision(10);
  graph_ << std::setprecision(10);
  check(telemetry_, dir_.telemetry());
  check(graph_, dir_.graph());
  check(events_, dir_.events());
  if (!mcap_.open(dir_.mcap()) && failed_.empty()) failed_ = dir_.mcap().string();
}

void RecordSinks::check(std::ofstream& f, const std::filesystem::path& path) {
  if (!f && failed_.empty()) failed_ = path.string();
}

void RecordSinks::write_record(const records::Record& r, std::int64_t published_wall_ns) {
  if (observer_) observer_->on_record(r, published_wall_ns);
  {
    google::protobuf::io::OstreamOutputStream raw(&records_);
    google::protobuf::io::CodedOutputStream out(&raw);
    out.WriteVarint32(static_cast<std::uint32_t>(r.ByteSizeLong()));
    r.SerializeWithCachedSizes(&out);
    if (out.HadError() && failed_.empty()) failed_ = dir_.records();
  }
  check(records_, dir_.records());
  // records.pb reaches the disk before each chunk of run.mcap does: a supervisor killed mid-run
  // leaves in records.pb at least what run.mcap holds, so `swarm export` can rebuild it.
  if (mcap_.chunk_due()) {
    records_.flush();
    check(records_, dir_.records());
  }
  mcap_.write(r);
  if (!mcap_.ok() && failed_.empty()) failed_ = dir_.mcap().string();
}

void RecordSinks::sample(const StateMessage& m, double age_ms) {
  const Vec3& q = m.view.q;
  const Eigen::Quaterniond& o = m.q_WB;
  telemetry_ << m.stamp_s << ',' << m.view.id << ',' << m.seq << ',' << int(m.phase) << ','
             << int(m.mode) << ',' << q.x() << ',' << q.y() << ',' << q.z() << ',' << m.p_W.x()
             << ',' << m.p_W.y() << ',' << m.p_W.z() << ',' << m.v_W.x() << ',' << m.v_W.y() << ','
             << m.v_W.z() << ',' << o.w() << ',' << o.x() << ',' << o.y() << ',' << o.z() << ','
             << m.rotors_radps[0] << ',' << m.rotors_radps[1] << ',' << m.rotors_radps[2] << ','
             << m.rotors_radps[3] << ',' << m.view.total_weight << ',' << m.links.size() << ','
             << age_ms << '\n';
  check(telemetry_, dir_.telemetry());
  records::Record r;
  records::AgentSample* s = r.mutable_sample();
  s->set_id(m.view.id);
  s->set_seq(m.seq);
  s->set_stamp_s(m.stamp_s);
  s->set_age_ms(age_ms);
  put_vec3(s->mutable_consensus(), q);
  put_vec3(s->mutable_position(), m.p_W);
  put_vec3(s->mutable_velocity(), m.v_W);
  s->add_orientation(o.w());
  s->add_orientation(o.x());
  s->add_orientation(o.y());
  s->add_orientation(o.z());
  for (int i = 0; i < 4; ++i) s->add_rotors(m.rotors_radps[i]);
  s->set_mode(static_cast<std::uint32_t>(m.mode));
  s->set_trimmed(m.trimmed);
  write_record(r, m.wall_ns);
}

void RecordSinks::graph(const records::GraphSnapshot& g) {
  std::ostringstream list;
  for (const records::GraphEdge& e : g.edges())
    list << (list.tellp() > 0 ? ";" : "") << e.a() << '-' << e.b() << ':' << e.weight();
  graph_ << g.t_s() << ',' << g.agents() << ',' << g.edges_size() << ',' << g.lambda2() << ','
         << g.components() << ',' << g.disagreement_m() << ',' << g.mean_drift_m() << ','
         << g.min_separation_m() << ',' << g.spread_m() << ",\"" << list.str() << "\","
         << g.min_degree() << ',' << (g.has_robust() ? int(g.robust()) : -1) << ','
         << g.trimmed_disagreement_m() << '\n';
  check(graph_, dir_.graph());
  records::Record r;
  *r.mutable_graph() = g;
  write_record(r);
}

void RecordSinks::event(double t_s, const std::string& kind, std::uint32_t agent,
                        const std::string& detail) {
  events_ << t_s << ',' << kind << ',' << agent << ',' << quoted(detail) << '\n';
  events_.flush();
  check(events_, dir_.events());
  records::Record r;
  records::Event* e = r.mutable_event();
  e->set_t_s(t_s);
  e->set_kind(kind);
  e->set_agent(agent);
  e->set_detail(detail);
  write_record(r);
}

bool RecordSinks::flush() {
  telemetry_.flush();
  check(telemetry_, dir_.telemetry());
  graph_.flush();
  check(graph_, dir_.graph());
  events_.flush();
  check(events_, dir_.events());
  records_.flush();
  check(records_, dir_.records());
  return ok();
}

bool RecordSinks::close() {
  flush();
  if (!mcap_.close() && failed_.empty()) failed_ = dir_.mcap().string();
  return ok();
}

}  // namespace qswarm
