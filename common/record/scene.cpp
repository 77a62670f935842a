#include "common/record/scene.hpp"

#include "common/record/json_writer.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>

namespace qswarm {
namespace {

struct Rgba {
  double r, g, b, a;
};

constexpr Rgba kAgent{1.0, 0.55, 0.1, 1.0};
constexpr Rgba kHeading{0.15, 0.15, 0.15, 1.0};
constexpr Rgba kLabel{1.0, 1.0, 1.0, 1.0};
constexpr Rgba kAgreement{0.1, 0.85, 0.3, 1.0};
constexpr Rgba kInitialAverage{1.0, 1.0, 1.0, 0.45};
constexpr Rgba kSlot{0.6, 0.6, 0.7, 0.35};
constexpr Rgba kLight{0.2, 0.45, 1.0, 0.9};  // the lightest link of the snapshot
constexpr Rgba kHeavy{1.0, 0.2, 0.2, 0.9};   // the heaviest

constexpr double kAgentDiameterM = 0.5;  // a quadcopter spans about 0.5 m (the paper's 0.25 m arms)
constexpr double kLinkThicknessM = 0.06;

// The scene's JSON, written by hand (JsonWriter): it goes out ten times a simulated second with
// up to hundreds of agents, and a DOM would cost more than the numbers. Positions to 0.1 mm,
// orientations to 1e-6, colours to 1/1000.
void vec3(JsonWriter& j, const Vec3& v) {
  j.raw("{\"x\":").num(v.x()).raw(",\"y\":").num(v.y()).raw(",\"z\":").num(v.z()).raw("}");
}

// orientation as w, x, y, z (the record's order); Foxglove's quaternion is x, y, z, w.
void pose(JsonWriter& j, const Vec3& p,
          const Eigen::Quaterniond& o = Eigen::Quaterniond::Identity()) {
  j.raw("{\"position\":");
  vec3(j, p);
  j.raw(",\"orientation\":{\"x\":").num(o.x(), 6).raw(",\"y\":").num(o.y(), 6);
  j.raw(",\"z\":").num(o.z(), 6).raw(",\"w\":").num(o.w(), 6).raw("}}");
}

void color(JsonWriter& j, const Rgba& c) {
  j.raw("{\"r\":").num(c.r, 3).raw(",\"g\":").num(c.g, 3).raw(",\"b\":").num(c.b, 3);
  j.raw(",\"a\":").num(c.a, 3).raw("}");
}

void stamp(JsonWriter& j, double t_s) {
  const double t = std::isfinite(t_s) ? std::max(0.0, t_s) : 0.0;
  const auto sec = static_cast<std::int64_t>(t);
  const auto nsec =
      std::min<std::int64_t>(999'999'999, std::llround((t - static_cast<double>(sec)) * 1e9));
  j.raw("{\"sec\":").integer(sec).raw(",\"nsec\":").integer(nsec).raw("}");
}

Vec3 vec3_of(const google::protobuf::RepeatedField<double>& f) {
  return f.size() >= 3 ? Vec3(f[0], f[1], f[2]) : Vec3(NAN, NAN, NAN);
}

bool finite(const Vec3& v) { return v.allFinite(); }

Eigen::Quaterniond orientation_of(const records::AgentSample& s) {
  const auto& o = s.orientation();
  if (o.size() < 4) return Eigen::Quaterniond::Identity();
  Eigen::Quaterniond q(o[0], o[1], o[2], o[3]);
  if (!std::isfinite(q.norm()) || q.norm() < 1e-9) return Eigen::Quaterniond::Identity();
  return q.normalized();
}

// The primitives of one entity, each array already as JSON items ("" when empty).
struct Entity {
  std::string id;
  std::vector<std::pair<std::string, std::string>> metadata;
  std::string arrows, cubes, spheres, lines, texts;
};

std::string sphere(const Vec3& p, double diameter_m, const Rgba& c) {
  std::string out;
  JsonWriter j(out);
  j.raw("{\"pose\":");
  pose(j, p);
  j.raw(",\"size\":");
  vec3(j, Vec3::Constant(diameter_m));
  j.raw(",\"color\":");
  color(j, c);
  j.raw("}");
  return out;
}

std::string cube(const Vec3& p, double side_m, const Rgba& c) { return sphere(p, side_m, c); }

std::string text(const Vec3& p, const std::string& s, const Rgba& c) {
  std::string out;
  JsonWriter j(out);
  j.raw("{\"pose\":");
  pose(j, p);
  j.raw(",\"billboard\":true,\"font_size\":14,\"scale_invariant\":true,\"color\":");
  color(j, c);
  j.raw(",\"text\":").str(s).raw("}");
  return out;
}

void write_entity(JsonWriter& j, const Entity& e, double t_s, const std::string& frame_id) {
  j.raw("{\"timestamp\":");
  stamp(j, t_s);
  j.raw(",\"frame_id\":").str(frame_id).raw(",\"id\":").str(e.id);
  j.raw(",\"lifetime\":{\"sec\":0,\"nsec\":0},\"frame_locked\":false,\"metadata\":[");
  for (std::size_t i = 0; i < e.metadata.size(); ++i) {
    j.raw(i ? "," : "").raw("{\"key\":").str(e.metadata[i].first);
    j.raw(",\"value\":").str(e.metadata[i].second).raw("}");
  }
  j.raw("],\"arrows\":[").raw(e.arrows).raw("],\"cubes\":[").raw(e.cubes);
  j.raw("],\"spheres\":[").raw(e.spheres).raw("],\"cylinders\":[],\"lines\":[").raw(e.lines);
  j.raw("],\"triangles\":[],\"texts\":[").raw(e.texts).raw("],\"models\":[]}");
}

std::string number_text(double v, int digits) {
  std::string out;
  JsonWriter(out).num(v, digits);
  return out;
}

// Links are drawn in kWeightBins classes of weight, each one line list over the agents' positions
// with indices into them: a complete graph of N agents then costs N positions per class and two
// indices per edge, not two positions and two colours per edge (32 agents all-to-all: 13 KB per
// scene instead of 97 KB).
constexpr int kWeightBins = 5;

int weight_bin(double w, double lo, double hi) {
  if (!(hi > lo) || !std::isfinite(w)) return kWeightBins / 2;
  return std::clamp(static_cast<int>((w - lo) / (hi - lo) * kWeightBins), 0, kWeightBins - 1);
}

Rgba bin_colour(int bin) {
  const double t = (bin + 0.5) / kWeightBins;
  return {kLight.r + t * (kHeavy.r - kLight.r), kLight.g + t * (kHeavy.g - kLight.g),
          kLight.b + t * (kHeavy.b - kLight.b), kLight.a};
}

}  // namespace

SceneSettings SceneSettings::of(const RunConfig& rc) {
  SceneSettings s;
  s.initial_average = rc.initial_average();
  if (rc.has_formation())
    for (const AgentSpec& a : rc.agents) s.offsets[a.id] = a.offset_W;
  return s;
}

std::string scene_update_json(const std::vector<records::AgentSample>& agents,
                              const records::GraphSnapshot& graph, const SceneSettings& settings) {
  const double t_s = graph.t_s();
  std::vector<Entity> entities;
  std::map<AgentId, Vec3> where;
  Vec3 sum = Vec3::Zero();
  int counted = 0;
  for (const records::AgentSample& s : agents) {
    const Vec3 p = vec3_of(s.position());
    if (!finite(p)) continue;
    where[s.id()] = p;
    if (const Vec3 q = vec3_of(s.consensus()); finite(q)) {
      sum += q;
      ++counted;
    }
    Entity e;
    e.id = "agent/" + std::to_string(s.id());
    e.metadata = {{"id", std::to_string(s.id())}, {"seq", std::to_string(s.seq())}};
    e.spheres = sphere(p, kAgentDiameterM, kAgent);
    if (s.mode() == static_cast<std::uint32_t>(PoseKind::kOriented)) {
      JsonWriter a(e.arrows);
      a.raw("{\"pose\":");
      pose(a, p, orientation_of(s));
      a.raw(",\"shaft_length\":0.45,\"shaft_diameter\":0.06,\"head_length\":0.2,");
      a.raw("\"head_diameter\":0.16,\"color\":");
      color(a, kHeading);
      a.raw("}");
    }
    e.texts = text(p + Vec3(0, 0, 0.6), std::to_string(s.id()), kLabel);
    entities.push_back(std::move(e));
  }

  Entity links;
  links.id = "links";
  links.metadata = {{"t_s", number_text(t_s, 3)},
                    {"lambda2", number_text(graph.lambda2(), 6)},
                    {"edges", std::to_string(graph.edges_size())},
                    {"disagreement_m", number_text(graph.disagreement_m(), 6)}};
  double lo = INFINITY, hi = -INFINITY;
  for (const records::GraphEdge& g : graph.edges()) {
    if (!std::isfinite(g.weight())) continue;
    lo = std::min(lo, g.weight());
    hi = std::max(hi, g.weight());
  }
  // Per class: the agents its edges touch (index in the line's points) and the index pairs.
  std::array<std::map<AgentId, std::uint32_t>, kWeightBins> used;
  std::array<std::vector<std::uint32_t>, kWeightBins> pairs;
  for (const records::GraphEdge& g : graph.edges()) {
    if (!where.count(g.a()) || !where.count(g.b())) continue;
    const auto bin = static_cast<std::size_t>(weight_bin(g.weight(), lo, hi));
    for (const AgentId id : {g.a(), g.b()}) {
      const auto [it, added] =
          used[bin].try_emplace(id, static_cast<std::uint32_t>(used[bin].size()));
      pairs[bin].push_back(it->second);
    }
  }
  for (std::size_t bin = 0; bin < used.size(); ++bin) {
    if (pairs[bin].empty()) continue;
    std::vector<const Vec3*> points(used[bin].size());
    for (const auto& [id, index] : used[bin]) points[index] = &where.at(id);
    JsonWriter l(links.lines);
    l.raw(links.lines.empty() ? "{\"type\":2,\"pose\":" : ",{\"type\":2,\"pose\":");
    pose(l, Vec3::Zero());
    l.raw(",\"thickness\":").num(kLinkThicknessM).raw(",\"scale_invariant\":false,\"points\":[");
    for (std::size_t i = 0; i < points.size(); ++i) {
      l.raw(i ? "," : "");
      vec3(l, *points[i]);
    }
    l.raw("],\"color\":");
    color(l, bin_colour(static_cast<int>(bin)));
    l.raw(",\"colors\":[],\"indices\":[");
    for (std::size_t i = 0; i < pairs[bin].size(); ++i) l.raw(i ? "," : "").integer(pairs[bin][i]);
    l.raw("]}");
  }
  if (std::isfinite(lo)) {
    links.metadata.emplace_back("weight_min", number_text(lo, 6));
    links.metadata.emplace_back("weight_max", number_text(hi, 6));
  }
  entities.push_back(std::move(links));

  if (counted) {
    const Vec3 mean = sum / counted;
    Entity agreement;
    agreement.id = "agreement";
    agreement.spheres = sphere(mean, 0.35, kAgreement);
    entities.push_back(std::move(agreement));
    for (const auto& [id, offset] : settings.offsets) {
      if (!where.count(id)) continue;
      Entity slot;
      slot.id = "slot/" + std::to_string(id);
      slot.cubes = cube(mean + offset, 0.3, kSlot);
      entities.push_back(std::move(slot));
    }
  }
  Entity ideal;
  ideal.id = "initial_average";
  ideal.spheres = sphere(settings.initial_average, 0.6, kInitialAverage);
  entities.push_back(std::move(ideal));

  std::string out;
  JsonWriter j(out);
  // Delete everything older than this message first: the message is the whole scene.
  j.raw("{\"deletions\":[{\"timestamp\":");
  stamp(j, t_s);
  j.raw(",\"type\":1,\"id\":\"\"}],\"entities\":[");
  for (std::size_t i = 0; i < entities.size(); ++i) {
    j.raw(i ? "," : "");
    write_entity(j, entities[i], t_s, settings.frame_id);
  }
  j.raw("]}");
  return out;
}

void SceneBuilder::on_event(const records::Event& e) {
  if (e.kind() == "depart") latest_.erase(e.agent());
}

std::string SceneBuilder::scene_json(const records::GraphSnapshot& graph) const {
  std::vector<records::AgentSample> agents;
  agents.reserve(latest_.size());
  for (const auto& [id, s] : latest_) agents.push_back(s);
  return scene_update_json(agents, graph, settings_);
}

namespace {

// JSON schema fragments, composed inline (no $ref: viewers derive their message paths from the
// schema, and not every one resolves references).
std::string object(const std::string& title,
                   const std::vector<std::pair<std::string, std::string>>& props) {
  std::string s = "{\"title\":\"" + title + "\",\"type\":\"object\",\"properties\":{";
  std::string required;
  for (std::size_t i = 0; i < props.size(); ++i) {
    s += (i ? ",\"" : "\"") + props[i].first + "\":" + props[i].second;
    required += (i ? ",\"" : "\"") + props[i].first + "\"";
  }
  return s + "},\"required\":[" + required + "]}";
}

std::string array_of(const std::string& item) {
  return "{\"type\":\"array\",\"items\":" + item + "}";
}

std::string scene_schema_text() {
  const std::string json_number = "{\"type\":\"number\"}";
  const std::string json_bool = "{\"type\":\"boolean\"}";
  const std::string json_string = "{\"type\":\"string\"}";
  const std::string json_count = "{\"type\":\"integer\",\"minimum\":0}";
  const std::string stamp = object("time", {{"sec", json_count}, {"nsec", json_count}});
  const std::string duration =
      object("duration", {{"sec", "{\"type\":\"integer\"}"}, {"nsec", json_count}});
  const std::string vec3 =
      object("foxglove.Vector3", {{"x", json_number}, {"y", json_number}, {"z", json_number}});
  const std::string point =
      object("foxglove.Point3", {{"x", json_number}, {"y", json_number}, {"z", json_number}});
  const std::string quat =
      object("foxglove.Quaternion",
             {{"x", json_number}, {"y", json_number}, {"z", json_number}, {"w", json_number}});
  const std::string pose = object("foxglove.Pose", {{"position", vec3}, {"orientation", quat}});
  const std::string color =
      object("foxglove.Color",
             {{"r", json_number}, {"g", json_number}, {"b", json_number}, {"a", json_number}});
  const std::string kv =
      object("foxglove.KeyValuePair", {{"key", json_string}, {"value", json_string}});
  const std::string arrow = object("foxglove.ArrowPrimitive", {{"pose", pose},
                                                               {"shaft_length", json_number},
                                                               {"shaft_diameter", json_number},
                                                               {"head_length", json_number},
                                                               {"head_diameter", json_number},
                                                               {"color", color}});
  const std::string cube =
      object("foxglove.CubePrimitive", {{"pose", pose}, {"size", vec3}, {"color", color}});
  const std::string sphere =
      object("foxglove.SpherePrimitive", {{"pose", pose}, {"size", vec3}, {"color", color}});
  const std::string cylinder = object("foxglove.CylinderPrimitive", {{"pose", pose},
                                                                     {"size", vec3},
                                                                     {"bottom_scale", json_number},
                                                                     {"top_scale", json_number},
                                                                     {"color", color}});
  const std::string line =
      object("foxglove.LinePrimitive", {{"type", "{\"type\":\"integer\",\"enum\":[0,1,2]}"},
                                        {"pose", pose},
                                        {"thickness", json_number},
                                        {"scale_invariant", json_bool},
                                        {"points", array_of(point)},
                                        {"color", color},
                                        {"colors", array_of(color)},
                                        {"indices", array_of(json_count)}});
  const std::string triangles =
      object("foxglove.TriangleListPrimitive", {{"pose", pose},
                                                {"points", array_of(point)},
                                                {"color", color},
                                                {"colors", array_of(color)},
                                                {"indices", array_of(json_count)}});
  const std::string text = object("foxglove.TextPrimitive", {{"pose", pose},
                                                             {"billboard", json_bool},
                                                             {"font_size", json_number},
                                                             {"scale_invariant", json_bool},
                                                             {"color", color},
                                                             {"text", json_string}});
  const std::string model = object("foxglove.ModelPrimitive", {{"pose", pose},
                                                               {"scale", vec3},
                                                               {"color", color},
                                                               {"override_color", json_bool},
                                                               {"url", json_string},
                                                               {"media_type", json_string},
                                                               {"data", json_string}});
  const std::string entity = object("foxglove.SceneEntity", {{"timestamp", stamp},
                                                             {"frame_id", json_string},
                                                             {"id", json_string},
                                                             {"lifetime", duration},
                                                             {"frame_locked", json_bool},
                                                             {"metadata", array_of(kv)},
                                                             {"arrows", array_of(arrow)},
                                                             {"cubes", array_of(cube)},
                                                             {"spheres", array_of(sphere)},
                                                             {"cylinders", array_of(cylinder)},
                                                             {"lines", array_of(line)},
                                                             {"triangles", array_of(triangles)},
                                                             {"texts", array_of(text)},
                                                             {"models", array_of(model)}});
  const std::string deletion =
      object("foxglove.SceneEntityDeletion", {{"timestamp", stamp},
                                              {"type", "{\"type\":\"integer\",\"enum\":[0,1]}"},
                                              {"id", json_string}});
  return object("foxglove.SceneUpdate",
                {{"deletions", array_of(deletion)}, {"entities", array_of(entity)}});
}

}  // namespace

std::string_view scene_update_json_schema() {
  static const std::string schema = scene_schema_text();
  return schema;
}

}  // namespace qswarm
