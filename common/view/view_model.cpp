#include "common/view/view_model.hpp"

#include <algorithm>

#include "common/core/update_law.hpp"
#include "common/record/json_writer.hpp"
#include "common/scenario/proto_util.hpp"

namespace qswarm {
namespace {

void vec3(JsonWriter& w, const Vec3& v, int decimals = 3) {
  w.raw("[").num(v.x(), decimals).raw(",").num(v.y(), decimals).raw(",").num(v.z(), decimals);
  w.raw("]");
}

void triple(JsonWriter& w, const google::protobuf::RepeatedField<double>& f, int decimals) {
  w.raw("[");
  for (int i = 0; i < 3; ++i) {
    if (i) w.raw(",");
    w.num(i < f.size() ? f.Get(i) : 0.0, decimals);
  }
  w.raw("]");
}

// [id, position, orientation (w x y z), consensus state, present, stamp]
void agent_json(JsonWriter& w, const records::AgentSample& s, bool present) {
  w.raw("[").integer(s.id()).raw(",");
  triple(w, s.position(), 3);
  w.raw(",[");
  for (int i = 0; i < 4; ++i) {
    if (i) w.raw(",");
    w.num(i < s.orientation_size() ? s.orientation(i) : (i == 0 ? 1.0 : 0.0), 4);
  }
  w.raw("],");
  triple(w, s.consensus(), 3);
  w.raw(",").boolean(present).raw(",").num(s.stamp_s(), 3).raw("]");
}

void graph_json(JsonWriter& w, const records::GraphSnapshot& g) {
  w.raw("{").key("t").num(g.t_s(), 3).raw(",").key("agents").integer(g.agents());
  w.raw(",").key("components").integer(g.components());
  w.raw(",").key("lambda2").sig(g.lambda2()).raw(",").key("disagreement").sig(g.disagreement_m());
  w.raw(",").key("drift").sig(g.mean_drift_m()).raw(",").key("min_sep").sig(g.min_separation_m());
  w.raw(",").key("spread").sig(g.spread_m()).raw(",").key("edges").raw("[");
  for (int i = 0; i < g.edges_size(); ++i) {
    const records::GraphEdge& e = g.edges(i);
    if (i) w.raw(",");
    w.raw("[").integer(e.a()).raw(",").integer(e.b()).raw(",").sig(e.weight()).raw("]");
  }
  w.raw("]}");
}

void metric_json(JsonWriter& w, double t, double l2, double dis, double drift, double sep) {
  w.raw("[").num(t, 3).raw(",").sig(l2).raw(",").sig(dis).raw(",").sig(drift).raw(",").sig(sep);
  w.raw("]");
}

void event_json(JsonWriter& w, const records::Event& e) {
  w.raw("{").key("t").num(e.t_s(), 3).raw(",").key("kind").str(e.kind()).raw(",");
  w.key("agent").integer(e.agent()).raw(",").key("detail").str(e.detail()).raw("}");
}

}  // namespace

std::string run_info_json(const RunConfig& rc) {
  std::string out;
  JsonWriter w(out);
  w.raw("{").key("name").str(rc.name).raw(",");
  w.key("mode").str(rc.agent.plant_spec().name).raw(",");
  w.key("law").str(rc.agent.law.law).raw(",");
  w.key("run_id").str(std::to_string(rc.transport.run_id)).raw(",");
  w.key("formation").boolean(rc.has_formation()).raw(",");
  w.key("tolerance_m").sig(rc.judge.tolerance_m).raw(",");
  w.key("duration_s").sig(rc.judge.duration_s).raw(",");
  w.key("safe_distance_m").sig(rc.agent.avoidance.safe_distance_m).raw(",");
  w.key("initial_average");
  vec3(w, rc.initial_average());
  w.raw(",").key("agents").raw("[");
  for (std::size_t i = 0; i < rc.agents.size(); ++i) {
    const AgentSpec& a = rc.agents[i];
    if (i) w.raw(",");
    w.raw("{").key("id").integer(a.id).raw(",").key("start");
    vec3(w, a.position_W);
    w.raw(",").key("offset");
    vec3(w, a.offset_W);
    w.raw(",").key("yaw").num(a.yaw_rad, 4).raw("}");
  }
  w.raw("]}");
  return out;
}

ViewModel::ViewModel(std::string run_info) : run_info_(std::move(run_info)) {}

void ViewModel::reset() {
  agents_.clear();
  graph_.reset();
  history_.clear();
  history_stride_ = 1;
  history_seen_ = 0;
  events_.clear();
  summary_json_.reset();
  t_s_ = 0.0;
}

void ViewModel::apply(const ViewBatch& b) {
  for (const ViewSample& s : b.samples) {
    Agent& a = agents_[s.sample.id()];
    a.sample = s.sample;
    t_s_ = std::max(t_s_, s.sample.stamp_s());
  }
  for (const records::GraphSnapshot& g : b.graphs) {
    graph_ = g;
    t_s_ = std::max(t_s_, g.t_s());
    if (history_seen_++ % history_stride_ != 0) continue;
    history_.push_back(
        {g.t_s(), g.lambda2(), g.disagreement_m(), g.mean_drift_m(), g.min_separation_m()});
    if (history_.size() >= kMaxHistory) {  // thin to every other point, and keep thinning so
      std::size_t k = 0;
      for (std::size_t i = 0; i < history_.size(); i += 2) history_[k++] = history_[i];
      history_.resize(k);
      history_stride_ *= 2;
    }
  }
  for (const records::Event& e : b.events) {
    if (e.kind() == "depart") agents_[e.agent()].present = false;
    if (e.kind() == "join" || e.kind() == "rejoin") agents_[e.agent()].present = true;
    if (events_.size() >= kMaxEvents) events_.erase(events_.begin() + kMaxEvents / 2);
    events_.push_back(e);
  }
  if (b.summary) summary_json_ = to_json(*b.summary);
}

std::string ViewModel::frame_json(const ViewBatch& b, std::int64_t now_wall_ns,
                                  const std::string& replay) const {
  std::string out;
  out.reserve(128 + b.samples.size() * 110);
  JsonWriter w(out);
  std::int64_t newest_pub_ns = 0;
  for (const ViewSample& s : b.samples)
    newest_pub_ns = std::max(newest_pub_ns, s.published_wall_ns);
  w.raw("{").key("type").str("frame").raw(",").key("t").num(t_s_, 3).raw(",");
  w.key("pub_ms").num(static_cast<double>(newest_pub_ns) * 1e-6, 1).raw(",");
  w.key("sent_ms").num(static_cast<double>(now_wall_ns) * 1e-6, 1).raw(",");
  w.key("agents").raw("[");
  for (std::size_t i = 0; i < b.samples.size(); ++i) {
    const auto it = agents_.find(b.samples[i].sample.id());
    if (i) w.raw(",");
    agent_json(w, b.samples[i].sample, it == agents_.end() || it->second.present);
  }
  w.raw("]");
  if (!b.graphs.empty()) {
    w.raw(",").key("graph");
    graph_json(w, b.graphs.back());
    w.raw(",").key("metrics").raw("[");
    for (std::size_t i = 0; i < b.graphs.size(); ++i) {
      const records::GraphSnapshot& g = b.graphs[i];
      if (i) w.raw(",");
      metric_json(w, g.t_s(), g.lambda2(), g.disagreement_m(), g.mean_drift_m(),
                  g.min_separation_m());
    }
    w.raw("]");
  }
  // Presence changes ride with the events that made them.
  w.raw(",").key("events").raw("[");
  for (std::size_t i = 0; i < b.events.size(); ++i) {
    if (i) w.raw(",");
    event_json(w, b.events[i]);
  }
  w.raw("]");
  if (b.summary && summary_json_) w.raw(",").key("summary").raw(*summary_json_);
  w.raw(",").key("replay").raw(replay).raw("}");
  return out;
}

std::string ViewModel::snapshot_json(const std::string& replay) const {
  std::string out;
  out.reserve(4096 + agents_.size() * 110 + history_.size() * 60);
  JsonWriter w(out);
  w.raw("{").key("type").str("snapshot").raw(",").key("run").raw(run_info_).raw(",");
  w.key("t").num(t_s_, 3).raw(",").key("agents").raw("[");
  bool first = true;
  for (const auto& [id, a] : agents_) {
    if (a.sample.id() != id) continue;  // known from an event only: no sample yet
    if (!first) w.raw(",");
    first = false;
    agent_json(w, a.sample, a.present);
  }
  w.raw("],").key("graph");
  if (graph_) {
    graph_json(w, *graph_);
  } else {
    w.raw("null");
  }
  w.raw(",").key("metrics").raw("[");
  for (std::size_t i = 0; i < history_.size(); ++i) {
    const Metric& m = history_[i];
    if (i) w.raw(",");
    metric_json(w, m.t_s, m.lambda2, m.disagreement_m, m.drift_m, m.min_separation_m);
  }
  w.raw("],").key("events").raw("[");
  for (std::size_t i = 0; i < events_.size(); ++i) {
    if (i) w.raw(",");
    event_json(w, events_[i]);
  }
  w.raw("],").key("summary").raw(summary_json_ ? *summary_json_ : "null");
  w.raw(",").key("replay").raw(replay).raw("}");
  return out;
}

}  // namespace qswarm
