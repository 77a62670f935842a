// The viewers' shared pieces: the channel catalogue (its schemas decode the record's messages) and
// the 3D scene a graph snapshot becomes.
#include <google/protobuf/descriptor.h>
#include <google/protobuf/descriptor.pb.h>
#include <google/protobuf/dynamic_message.h>
#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "common/record/channels.hpp"
#include "common/record/scene.hpp"

namespace qswarm {
namespace {

namespace pb = google::protobuf;

pb::Value parse_json(std::string_view text) {
  pb::Value v;
  const auto status = pb::util::JsonStringToMessage(std::string(text), &v);
  EXPECT_TRUE(status.ok()) << status.ToString() << "\n" << text.substr(0, 300);
  return v;
}

const pb::Value& field(const pb::Value& v, const std::string& key) {
  static const pb::Value missing;
  const auto& f = v.struct_value().fields();
  const auto it = f.find(key);
  EXPECT_NE(it, f.end()) << "no field " << key;
  return it == f.end() ? missing : it->second;
}

Vec3 vec3(const pb::Value& v) {
  return {field(v, "x").number_value(), field(v, "y").number_value(), field(v, "z").number_value()};
}

records::AgentSample agent(AgentId id, const Vec3& p, const Vec3& q, std::uint32_t mode = 1) {
  records::AgentSample s;
  s.set_id(id);
  s.set_seq(7);
  s.set_stamp_s(2.5);
  for (int k = 0; k < 3; ++k) s.add_position(p[k]);
  for (int k = 0; k < 3; ++k) s.add_consensus(q[k]);
  const Eigen::Quaterniond o(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitZ()));  // heading +y
  s.add_orientation(o.w());
  s.add_orientation(o.x());
  s.add_orientation(o.y());
  s.add_orientation(o.z());
  s.set_mode(mode);
  return s;
}

records::GraphSnapshot graph(double t_s, std::vector<std::tuple<AgentId, AgentId, double>> edges) {
  records::GraphSnapshot g;
  g.set_t_s(t_s);
  g.set_lambda2(1.5);
  for (const auto& [a, b, w] : edges) {
    records::GraphEdge* e = g.add_edges();
    e->set_a(a);
    e->set_b(b);
    e->set_weight(w);
  }
  return g;
}

std::map<std::string, pb::Value> entities_by_id(const pb::Value& scene) {
  std::map<std::string, pb::Value> out;
  for (const pb::Value& e : field(scene, "entities").list_value().values())
    out[field(e, "id").string_value()] = e;
  return out;
}

TEST(ChannelCatalogue, ListsEveryStreamOnceInTheOrderOfTheEnum) {
  std::set<std::string_view> topics;
  for (std::size_t i = 0; i < kStreamCount; ++i) {
    const ChannelInfo& c = channel_catalogue()[i];
    EXPECT_EQ(static_cast<std::size_t>(c.stream), i);
    EXPECT_TRUE(topics.insert(c.topic).second) << c.topic;
    EXPECT_FALSE(c.schema.empty()) << c.topic;
    EXPECT_EQ(c.message_encoding == "protobuf", c.schema_encoding == "protobuf") << c.topic;
  }
  EXPECT_EQ(channel_info(Stream::kScene).schema_name, "foxglove.SceneUpdate");
  EXPECT_EQ(channel_info(Stream::kScene).message_encoding, "json");
  EXPECT_EQ(channel_info(Stream::kScene).schema_encoding, "jsonschema");
}

// A reader that knows nothing of the generated classes (as a viewer) builds the message types from
// the advertised FileDescriptorSet and decodes the record's bytes with them.
TEST(ChannelCatalogue, TheProtobufSchemasAreAFileDescriptorSetThatDecodesTheRecord) {
  for (const Stream s : {Stream::kAgentSamples, Stream::kGraph, Stream::kEvents}) {
    const ChannelInfo& c = channel_info(s);
    pb::FileDescriptorSet set;
    ASSERT_TRUE(set.ParseFromArray(c.schema.data(), static_cast<int>(c.schema.size())));
    pb::DescriptorPool pool;  // not the generated pool: only what the bytes say
    for (const pb::FileDescriptorProto& f : set.file()) ASSERT_NE(pool.BuildFile(f), nullptr);
    const pb::Descriptor* d = pool.FindMessageTypeByName(std::string(c.schema_name));
    ASSERT_NE(d, nullptr) << c.schema_name;
    pb::DynamicMessageFactory factory(&pool);
    std::unique_ptr<pb::Message> m(factory.GetPrototype(d)->New());
    if (s == Stream::kAgentSamples) {
      ASSERT_TRUE(m->ParseFromString(agent(3, {1, 2, 3}, {4, 5, 6}).SerializeAsString()));
      const pb::FieldDescriptor* id = d->FindFieldByName("id");
      const pb::FieldDescriptor* position = d->FindFieldByName("position");
      EXPECT_EQ(m->GetReflection()->GetUInt32(*m, id), 3u);
      EXPECT_EQ(m->GetReflection()->GetRepeatedDouble(*m, position, 2), 3.0);
    }
  }
}

TEST(Scene, TheJsonSchemaIsJsonNamedForFoxglove) {
  const pb::Value schema = parse_json(scene_update_json_schema());
  EXPECT_EQ(field(schema, "title").string_value(), "foxglove.SceneUpdate");
  const pb::Value& entity = field(field(field(schema, "properties"), "entities"), "items");
  EXPECT_EQ(field(entity, "title").string_value(), "foxglove.SceneEntity");
  EXPECT_EQ(field(entity, "required").list_value().values_size(), 14);
}

TEST(Scene, DrawsAgentsLinksTheAgreementPointTheIdealAndTheSlots) {
  SceneSettings settings;
  settings.initial_average = {1, 1, 1};
  settings.offsets = {{1, {-1, 0, 0}}, {2, {1, 0, 0}}, {3, {0, 2, 0}}};
  const std::vector<records::AgentSample> agents = {agent(1, {0, 0, 10}, {0, 0, 0}),
                                                    agent(2, {4, 0, 10}, {3, 0, 0}),
                                                    agent(3, {0, 4, 10}, {0, 6, 3})};
  const std::string json =
      scene_update_json(agents, graph(12.25, {{1, 2, 0.5}, {2, 3, 4.0}}), settings);
  const pb::Value scene = parse_json(json);

  // Everything older than this message goes: the message is the whole scene.
  const auto& deletions = field(scene, "deletions").list_value();
  ASSERT_EQ(deletions.values_size(), 1);
  EXPECT_EQ(field(deletions.values(0), "type").number_value(), 1.0);  // ALL
  EXPECT_EQ(field(field(deletions.values(0), "timestamp"), "sec").number_value(), 12.0);
  EXPECT_EQ(field(field(deletions.values(0), "timestamp"), "nsec").number_value(), 250000000.0);

  auto e = entities_by_id(scene);
  for (const char* id : {"agent/1", "agent/2", "agent/3", "links", "agreement", "initial_average",
                         "slot/1", "slot/2", "slot/3"})
    EXPECT_TRUE(e.count(id)) << id;
  EXPECT_EQ(e.size(), 9u);

  const pb::Value& a2 = e["agent/2"];
  EXPECT_EQ(field(a2, "frame_id").string_value(), "world");
  const pb::Value& sphere = field(a2, "spheres").list_value().values(0);
  EXPECT_EQ(vec3(field(field(sphere, "pose"), "position")), Vec3(4, 0, 10));
  // The heading: the arrow's orientation is the body's (+90 degrees about z), x y z w.
  const pb::Value& arrow = field(a2, "arrows").list_value().values(0);
  const pb::Value& o = field(field(arrow, "pose"), "orientation");
  EXPECT_NEAR(field(o, "z").number_value(), std::sqrt(0.5), 1e-6);
  EXPECT_NEAR(field(o, "w").number_value(), std::sqrt(0.5), 1e-6);
  EXPECT_EQ(field(field(a2, "texts").list_value().values(0), "text").string_value(), "2");

  // Links between positions, one line list per class of weight; the heavier edge is redder.
  const auto& lines = field(e["links"], "lines").list_value();
  ASSERT_EQ(lines.values_size(), 2);  // 0.5 and 4.0: the lightest and the heaviest class
  const auto segment = [&](int line) {
    const pb::Value& l = lines.values(line);
    EXPECT_EQ(field(l, "type").number_value(), 2.0);  // LINE_LIST
    const auto& points = field(l, "points").list_value();
    const auto& indices = field(l, "indices").list_value();
    EXPECT_EQ(indices.values_size(), 2);
    return std::pair{vec3(points.values(static_cast<int>(indices.values(0).number_value()))),
                     vec3(points.values(static_cast<int>(indices.values(1).number_value())))};
  };
  EXPECT_EQ(segment(0), std::pair(Vec3(0, 0, 10), Vec3(4, 0, 10)));  // 1-2, weight 0.5
  EXPECT_EQ(segment(1), std::pair(Vec3(4, 0, 10), Vec3(0, 4, 10)));  // 2-3, weight 4
  EXPECT_LT(field(field(lines.values(0), "color"), "r").number_value(),
            field(field(lines.values(1), "color"), "r").number_value());

  // The agreement point is the mean of the consensus states; slots are about it.
  const Vec3 mean(1, 2, 1);
  const auto centre = [&](const std::string& id, const char* kind) {
    return vec3(field(field(field(e[id], kind).list_value().values(0), "pose"), "position"));
  };
  EXPECT_EQ(centre("agreement", "spheres"), mean);
  EXPECT_EQ(centre("initial_average", "spheres"), Vec3(1, 1, 1));
  EXPECT_EQ(centre("slot/3", "cubes"), mean + Vec3(0, 2, 0));
}

TEST(Scene, AnAgentWithoutAFinitePositionAndItsEdgesAreLeftOut) {
  std::vector<records::AgentSample> agents = {agent(1, {0, 0, 0}, {0, 0, 0}),
                                              agent(2, {NAN, 0, 0}, {1, 0, 0}),
                                              agent(3, {1, 0, 0}, {2, 0, 0}, 0)};
  const pb::Value scene = parse_json(
      scene_update_json(agents, graph(1, {{1, 2, 1}, {1, 3, 1}, {3, 9, 1}}), SceneSettings{}));
  auto e = entities_by_id(scene);
  EXPECT_FALSE(e.count("agent/2"));
  EXPECT_FALSE(e.count("slot/1"));                                         // no formation
  EXPECT_EQ(field(e["agent/3"], "arrows").list_value().values_size(), 0);  // a particle
  const pb::Value& line = field(e["links"], "lines").list_value().values(0);
  EXPECT_EQ(field(line, "points").list_value().values_size(), 2);  // only 1-3
  EXPECT_EQ(field(line, "indices").list_value().values_size(), 2);
  // The mean of 1's and 3's consensus states (2's position is not finite).
  const pb::Value& agreement = field(e["agreement"], "spheres").list_value().values(0);
  EXPECT_EQ(vec3(field(field(agreement, "pose"), "position")), Vec3(1, 0, 0));
}

TEST(Scene, ABuilderForgetsADepartedAgentUntilItIsHeardAgain) {
  SceneBuilder b(SceneSettings{});
  b.on_sample(agent(1, {0, 0, 0}, {0, 0, 0}));
  b.on_sample(agent(2, {1, 0, 0}, {0, 0, 0}));
  records::Event depart;
  depart.set_kind("depart");
  depart.set_agent(2);
  b.on_event(depart);
  EXPECT_FALSE(entities_by_id(parse_json(b.scene_json(graph(1, {})))).count("agent/2"));
  b.on_sample(agent(2, {1, 0, 0}, {0, 0, 0}));
  EXPECT_TRUE(entities_by_id(parse_json(b.scene_json(graph(2, {})))).count("agent/2"));
}

TEST(Scene, NamesWithQuotesAndControlCharactersStayJson) {
  SceneSettings s;
  s.frame_id = "w\"or\\ld\n";
  const pb::Value scene =
      parse_json(scene_update_json({agent(1, {1e20, -0.0, 1e-9}, {0, 0, 0})}, graph(-3, {}), s));
  EXPECT_EQ(field(entities_by_id(scene)["agent/1"], "frame_id").string_value(), "w\"or\\ld\n");
}

}  // namespace
}  // namespace qswarm
