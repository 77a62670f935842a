// The scenario resolver is a pure function: every bad field is refused with its name, in-process.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>

#include "common/scenario/fault_flags.hpp"
#include "common/scenario/scenario.hpp"

namespace qswarm {
namespace {

const std::string kTwo =
    "agents { id: 1 position { x: 0 y: 0 z: 0 } }\nagents { id: 2 position { x: 1 y: 0 z: 0 } }\n";

std::string error_of(const std::string& text) {
  try {
    resolve_scenario(parse_scenario_text(text, "s.txtpb"));
  } catch (const ScenarioError& e) {
    return e.what();
  }
  return "";
}

TEST(Scenario, EveryBadFieldIsRefusedWithItsName) {
  struct Case {
    std::string text, expect;
  };
  const std::vector<Case> cases = {
      {"name: \"x\"\nagnets { id: 1 }\n", "s.txtpb:2:"},  // syntax: line
      {"name: \"x\"\nagnets { id: 1 }\n", "agnets"},
      {kTwo + "agents { id: 2 position { x: 5 } }\n", "agents[2].id"},  // duplicate
      {kTwo + "topology { threshold_m: -3 }\n", "topology.threshold_m"},
      {"agents { id: 1 position { x: nan } }\n", "agents[0].position"},
      {kTwo + "topology { policy: FIXED edges { a: 1 b: 9 } }\n", "topology.edges[0].b"},
      {kTwo + "mode: QUADCOPTER\nrates { physics_hz: 100 }\n", "rates.physics_hz"},
      {kTwo + "law: GOSSIP\n", "GOSSIP"},
      {kTwo + "law_name: \"gossip\"\n", "law_name"},
      {kTwo + "law: LAPLACIAN\nlaw_name: \"w-msr\"\n", "law_name"},
      {kTwo + "law_name: \"w-msr\"\nlaw_params { key: \"f\" value: 2.5 }\n", "law_params[\"f\"]"},
      {kTwo + "law_name: \"w-msr\"\nlaw_params { key: \"f\" value: nan }\n", "law_params[\"f\"]"},
      {kTwo + "law_params { key: \"f\" value: 1 }\n", "law_params[\"f\"]"},  // edge-flow's
      {kTwo + "law: W_MSR\nwmsr_f: 1\nlaw_params { key: \"f\" value: 1 }\n", "wmsr_f"},
      {kTwo + "law: LAPLACIAN\nwmsr_f: 1\n", "wmsr_f"},
      {"", "agents"},
      {kTwo + "faults { loss { probability: 1.5 } }\n", "faults.loss[0].probability"},
      {kTwo + "faults { cut { a: 1 b: 7 start_s: 1 end_s: 2 } }\n", "faults.cut[0].b"},
      {kTwo + "faults { partition { group: 1 start_s: 5 end_s: 3 } }\n",
       "faults.partition[0].end_s"},
      {kTwo + "faults { kill { agent: 2 at_s: 5 restart_at_s: 4 } }\n",
       "faults.kill[0].restart_at_s"},
      // Values that pass a type check but no run can honour.
      {kTwo + "rates { physics_hz: 500 consensus_hz: 30 }\n", "rates.consensus_hz"},  // 500/30
      {kTwo + "rates { consensus_hz: 0.001 }\n", "rates.consensus_hz"},
      {kTwo + "duration_s: nan\n", "duration_s"},
      {kTwo + "duration_s: inf\n", "duration_s"},
      {kTwo + "gain: 1e300\n", "gain"},
      {kTwo + "weight { scale: 1e12 }\n", "weight.scale"},
      {kTwo + "transport { neighbor_timeout_s: 0.001 }\n", "transport.neighbor_timeout_s"},
      {kTwo + "convergence { hold_s: -1 }\n", "convergence.hold_s"},
      {kTwo + "faults { delay { mean_s: nan } }\n", "faults.delay[0].mean_s"},
      {kTwo + "faults { kill { agent: 2 at_s: inf } }\n", "faults.kill[0].at_s"},
      {kTwo + "faults { late_join { agent: 2 at_s: 1 } late_join { agent: 2 at_s: 2 } }\n",
       "faults.late_join[1].agent"},
      {"random_agents { count: 513 }\n", "random_agents.count"},
      {"random_agents { count: 3 box_m: nan }\n", "random_agents.box_m"},
      // Collision avoidance: a point agent cannot have it; the distance must be one a run honours;
      // a run must not start in a violation (listed or random starts).
      {kTwo + "avoidance { enabled: true }\n", "avoidance.enabled"},
      {kTwo + "mode: QUADCOPTER\navoidance { safe_distance_m: nan }\n",
       "avoidance.safe_distance_m"},
      {kTwo + "avoidance { safe_distance_m: 0 }\n", "avoidance.safe_distance_m"},
      {kTwo + "avoidance { safe_distance_m: 1e9 }\n", "avoidance.safe_distance_m"},
      {kTwo + "mode: QUADCOPTER\navoidance { safe_distance_m: 0.3 }\n",
       "avoidance.safe_distance_m"},
      {kTwo + "mode: QUADCOPTER\navoidance { safe_distance_m: 1.5 }\n", "agents[1].position"},
      {"mode: QUADCOPTER\nrandom_agents { count: 64 box_m: 2 }\n", "random_agents.box_m"},
  };
  for (const Case& c : cases) {
    const std::string why = error_of(c.text);
    EXPECT_NE(why.find(c.expect), std::string::npos)
        << "scenario:\n"
        << c.text << "expected '" << c.expect << "' in: '" << why << "'";
  }
}

// A name or description is text a viewer shows and the record keeps: bytes that are not UTF-8
// are refused, naming the field; any UTF-8 passes.
TEST(Scenario, ANameOrDescriptionThatIsNotUtf8IsRefusedNamingIt) {
  const std::string agents = "agents { id: 1 } agents { id: 2 position { x: 1 } }\n";
  EXPECT_NE(error_of(agents + "name: \"bad\\377\"").find("scenario field 'name'"),
            std::string::npos);
  EXPECT_NE(error_of(agents + "description: \"cut \\342\\202\"").find("'description'"),
            std::string::npos);
  EXPECT_EQ(error_of(agents + "name: \"caf\\303\\251 \\360\\237\\232\\201\""), "");
}

TEST(Scenario, AvoidanceIsOnForQuadcoptersOffForParticlesAndKeepsRandomStartsApart) {
  const RunConfig quad = resolve_scenario(parse_scenario_text(
      "mode: QUADCOPTER\nrandom_agents { count: 40 box_m: 6 }\nseed: 3\n", "s"));
  EXPECT_TRUE(quad.agent.avoidance.enabled);
  EXPECT_EQ(quad.agent.avoidance.safe_distance_m, 1.0);
  double closest = 1e300;
  for (const AgentSpec& a : quad.agents)
    for (const AgentSpec& b : quad.agents)
      if (a.id != b.id) closest = std::min(closest, (a.position_W - b.position_W).norm());
  EXPECT_GE(closest, 1.0);  // 40 in a 6 m cube: a plain draw would put some closer
  EXPECT_TRUE(quad.resolved.avoidance().enabled());  // the record's scenario says what ran
  EXPECT_EQ(quad.resolved.avoidance().safe_distance_m(), 1.0);

  const RunConfig particle = resolve_scenario(parse_scenario_text(kTwo, "s"));
  EXPECT_FALSE(particle.agent.avoidance.enabled);
  const RunConfig off = resolve_scenario(parse_scenario_text(
      kTwo + "mode: QUADCOPTER\navoidance { enabled: false safe_distance_m: 2 }\n", "s"));
  EXPECT_FALSE(off.agent.avoidance.enabled);  // and listed starts closer than 2 m are then allowed
  EXPECT_EQ(off.agent.avoidance.safe_distance_m, 2.0);  // still what the record judges by
  // Held agents: slots closer than the filter keeps quadcopters apart.
  EXPECT_EQ(particle.held_agents().size(), 0u);
  const std::string four = "mode: QUADCOPTER\nrandom_agents { count: 4 box_m: 20 }\n";
  EXPECT_EQ(resolve_scenario(parse_scenario_text(four, "s")).held_agents().size(),
            4u);  // one point
  EXPECT_EQ(
      resolve_scenario(parse_scenario_text(four + "formation { shape: GRID spacing_m: 3 }\n", "s"))
          .held_agents()
          .size(),
      0u);
  EXPECT_EQ(
      resolve_scenario(parse_scenario_text(four + "formation { shape: LINE spacing_m: 1 }\n", "s"))
          .held_agents()
          .size(),
      4u);
  // Without avoidance the random draw is the plain one (the paper's scenarios keep their starts).
  const RunConfig plain =
      resolve_scenario(parse_scenario_text("random_agents { count: 40 box_m: 6 }\nseed: 3\n", "s"));
  const std::vector<AgentSpec> uniform = random_agent_specs(40, 3, 6.0);
  for (std::size_t i = 0; i < uniform.size(); ++i)
    EXPECT_EQ(plain.agents[i].position_W, uniform[i].position_W);
}

TEST(Scenario, SwarmsBeyondWhatTheWireCarriesAreRefusedAndTheBoundItselfIsAccepted) {
  std::string at_bound, beyond;
  for (int i = 1; i <= static_cast<int>(kMaxSwarmAgents) + 1; ++i) {
    const std::string a =
        "agents { id: " + std::to_string(i) + " position { x: " + std::to_string(i) + " } }\n";
    if (i <= static_cast<int>(kMaxSwarmAgents)) at_bound += a;
    beyond += a;
  }
  EXPECT_EQ(resolve_scenario(parse_scenario_text(at_bound, "s")).agents.size(), kMaxSwarmAgents);
  EXPECT_NE(error_of(beyond).find("at most 512 agents"), std::string::npos) << error_of(beyond);
}

TEST(Scenario, DiscoveryIsThroughAServerAbove32PlainAgentsAndSecureRunsCannotAskForOne) {
  const auto discovery = [](const std::string& text) {
    return resolve_scenario(parse_scenario_text(text, "s")).plan.discovery;
  };
  EXPECT_EQ(discovery("random_agents { count: 32 }\n"), DiscoveryMode::kMulticast);
  EXPECT_EQ(discovery("random_agents { count: 33 }\n"), DiscoveryMode::kServer);
  EXPECT_EQ(discovery("random_agents { count: 33 }\ntransport { discovery: SIMPLE }\n"),
            DiscoveryMode::kMulticast);
  EXPECT_EQ(discovery(kTwo + "transport { discovery: SERVER }\n"), DiscoveryMode::kServer);
  // A secure run (a keystore; any directory passes the resolver, `swarm keys --check` judges it).
  const std::string keystore =
      "transport { keystore: \"" + std::filesystem::temp_directory_path().string() + "\" ";
  EXPECT_NE(error_of(kTwo + keystore + "discovery: SERVER }\n").find("transport.discovery"),
            std::string::npos);
  EXPECT_EQ(
      resolve_scenario(parse_scenario_text("random_agents { count: 64 }\n" + keystore + "}\n", "s"))
          .plan.discovery,
      DiscoveryMode::kUnicastBlock);
  // The scenario as run says which was used.
  const RunConfig rc = resolve_scenario(
      parse_scenario_text("random_agents { count: 4 }\ntransport { discovery: SERVER }\n", "s"));
  EXPECT_EQ(rc.resolved.transport().discovery(), scenario::Transport::SERVER);
  EXPECT_EQ(resolve_scenario(parse_scenario_text(kTwo, "s")).resolved.transport().discovery(),
            scenario::Transport::SIMPLE);
}

TEST(Scenario, TheRecordRateFallsAbove128AgentsUnlessTheScenarioSetsIt) {
  const auto record_hz = [](const std::string& text) {
    return resolve_scenario(parse_scenario_text(text, "s")).plan.record_hz;
  };
  // 50 Hz consensus: the supervisor gets every k-th sample, k = 50 / rate rounded.
  const std::string rates = "rates { consensus_hz: 50 physics_hz: 50 }\n";
  EXPECT_EQ(record_hz("random_agents { count: 8 }\n" + rates), 10.0);
  EXPECT_EQ(record_hz("random_agents { count: 128 }\n" + rates), 10.0);
  EXPECT_EQ(record_hz("random_agents { count: 256 }\n" + rates), 5.0);
  EXPECT_EQ(record_hz("random_agents { count: 512 }\n" + rates), 2.5);
  EXPECT_EQ(record_hz("random_agents { count: 512 }\n" + rates + "record { rate_hz: 10 }\n"), 10.0);
  // Written back, so the agents (which resolve the scenario as run) send at the same rate.
  const RunConfig rc =
      resolve_scenario(parse_scenario_text("random_agents { count: 256 }\n" + rates, "s"));
  EXPECT_EQ(rc.resolved.record().rate_hz(), 5.0);
  EXPECT_EQ(rc.plan.record_every, 10u);
}

TEST(Scenario, DefaultsAreWrittenBackSoTheRecordSaysWhatRan) {
  const RunConfig rc = resolve_scenario(parse_scenario_text(kTwo, "s"));
  EXPECT_DOUBLE_EQ(rc.resolved.rates().consensus_hz(), 50.0);
  EXPECT_DOUBLE_EQ(rc.resolved.transport().neighbor_timeout_s(), 1.0);
  EXPECT_EQ(rc.resolved.transport().interface(), "127.0.0.1");
  const RunConfig again = resolve_scenario(parse_scenario_text(to_text(rc.resolved), "again"));
  EXPECT_EQ(to_text(again.resolved), to_text(rc.resolved));
}

TEST(Scenario, ALawIsNamedWithItsParametersAndTheScenarioAsRunSaysThemAll) {
  // The enum of the shipped laws and law_name are two spellings of one choice.
  const RunConfig by_enum = resolve_scenario(parse_scenario_text(kTwo + "law: W_MSR\n", "s"));
  const RunConfig by_name = resolve_scenario(
      parse_scenario_text(kTwo + "law_name: \"wmsr\"\nlaw_params { key: \"f\" value: 2 }\n", "s"));
  EXPECT_EQ(by_enum.agent.law.law, "w-msr");
  EXPECT_EQ(by_enum.agent.law.params, (std::map<std::string, double>{{"f", 1.0}}));
  EXPECT_EQ(by_name.agent.law.law, "w-msr");
  EXPECT_EQ(by_name.agent.law.params.at("f"), 2.0);
  // The legacy field still says F.
  const RunConfig legacy =
      resolve_scenario(parse_scenario_text(kTwo + "law: W_MSR\nwmsr_f: 3\n", "s"));
  EXPECT_EQ(legacy.agent.law.params.at("f"), 3.0);
  // Written back: every parameter, read again to the same run.
  EXPECT_EQ(legacy.resolved.law_params().at("f"), 3.0);
  EXPECT_FALSE(legacy.resolved.has_wmsr_f());
  const RunConfig again = resolve_scenario(parse_scenario_text(to_text(legacy.resolved), "again"));
  EXPECT_EQ(again.agent.law.law, "w-msr");
  EXPECT_EQ(again.agent.law.params, legacy.agent.law.params);
  // --law overrides the scenario's law, and drops parameters that were another law's.
  ScenarioOverrides o;
  o.law = "laplacian";
  const RunConfig over =
      resolve_scenario(parse_scenario_text(kTwo + "law: W_MSR\nwmsr_f: 3\n", "s"), o);
  EXPECT_EQ(over.agent.law.law, "laplacian");
  EXPECT_TRUE(over.agent.law.params.empty());
  o.law = "gossip";
  try {
    resolve_scenario(parse_scenario_text(kTwo, "s"), o);
    ADD_FAILURE() << "--law gossip accepted";
  } catch (const ScenarioError& e) {
    EXPECT_NE(std::string(e.what()).find("'--law'"), std::string::npos) << e.what();
  }
}

TEST(Scenario, APlantIsNamedWithItsParametersAndChecksTheRatesAndAvoidanceItNeeds) {
  // The enum of the shipped plants and `plant` are two spellings of one choice.
  const RunConfig by_enum = resolve_scenario(parse_scenario_text(kTwo + "mode: QUADCOPTER\n", "s"));
  const RunConfig by_name =
      resolve_scenario(parse_scenario_text(kTwo + "plant: \"quadcopter\"\n", "s"));
  EXPECT_EQ(by_enum.agent.plant.name, "quadcopter");
  EXPECT_EQ(by_name.agent.plant.name, "quadcopter");
  EXPECT_TRUE(by_name.agent.avoidance.enabled);  // on by default for a plant that flies
  EXPECT_EQ(resolve_scenario(parse_scenario_text(kTwo, "s")).agent.plant.name, "particle");
  EXPECT_EQ(
      resolve_scenario(parse_scenario_text(kTwo + "plant: \"point\"\n", "s")).agent.plant.name,
      "particle");
  // Read again from the scenario as run: the same plant.
  const RunConfig again = resolve_scenario(parse_scenario_text(to_text(by_name.resolved), "again"));
  EXPECT_EQ(again.agent.plant.name, "quadcopter");
  // --plant overrides the scenario's plant (and `mode`).
  ScenarioOverrides o;
  o.plant = "point";
  EXPECT_EQ(
      resolve_scenario(parse_scenario_text(kTwo + "mode: QUADCOPTER\n", "s"), o).agent.plant.name,
      "particle");
  o.plant = "hexacopter";
  try {
    resolve_scenario(parse_scenario_text(kTwo, "s"), o);
    ADD_FAILURE() << "--plant hexacopter accepted";
  } catch (const ScenarioError& e) {
    EXPECT_NE(std::string(e.what()).find("'--plant'"), std::string::npos) << e.what();
  }
  // Its parameters are kept by --plant naming the same plant (by an alias too) and dropped with the
  // avoidance switch of a scenario as run when it names another.
  const std::string pm =
      kTwo + "plant: \"point-mass\"\nplant_params { key: \"damping\" value: 2 }\n";
  const RunConfig as_run = resolve_scenario(parse_scenario_text(pm, "s"));
  EXPECT_EQ(as_run.agent.plant.params.at("damping"), 2.0);
  EXPECT_EQ(as_run.agent.plant.params.size(), 3u);  // every parameter written back
  const scenario::Scenario written = parse_scenario_text(to_text(as_run.resolved), "as run");
  EXPECT_EQ(resolve_scenario(written).agent.plant.params, as_run.agent.plant.params);
  o.plant = "double-integrator";
  EXPECT_EQ(resolve_scenario(written, o).agent.plant.params, as_run.agent.plant.params);
  o.plant = "particle";
  const RunConfig switched = resolve_scenario(written, o);
  EXPECT_TRUE(switched.agent.plant.params.empty());
  EXPECT_FALSE(switched.agent.avoidance.enabled);
  // A mode beyond the enum is refused, not read as a point agent.
  scenario::Scenario odd = parse_scenario_text(kTwo, "s");
  odd.set_mode(static_cast<scenario::Mode>(7));
  try {
    resolve_scenario(odd);
    ADD_FAILURE() << "mode 7 accepted";
  } catch (const ScenarioError& e) {
    EXPECT_NE(std::string(e.what()).find("'mode'"), std::string::npos) << e.what();
  }
  // What it needs is checked by its spec, named by field.
  for (const auto& [text, field] : std::vector<std::pair<std::string, std::string>>{
           {"plant: \"point-mass\"\nrates { physics_hz: 100 }\n", "'rates.physics_hz'"},
           // It could not follow avoidance's braking (4.5 m/s^2), nor a reference of 8 m/s^2.
           {"plant: \"point-mass\"\nplant_params { key: \"max_accel_mps2\" value: 3 }\n",
            "'plant_params'"},
           {"plant: \"point-mass\"\navoidance { enabled: false }\nlimits { "
            "reference_accel_mps2: 8 }\n",
            "accelerating at most 6 m/s^2"},
           {"plant: \"hexacopter\"\n", "'plant'"},
           {"plant: \"quadcopter\"\nmode: PARTICLE\n", "'plant'"},
           {"plant: \"quadcopter\"\nrates { physics_hz: 100 }\n", "'rates.physics_hz'"},
           {"plant: \"particle\"\navoidance { enabled: true }\n", "'avoidance.enabled'"},
           {"plant: \"quadcopter\"\nplant_params { key: \"mass_kg\" value: 1 }\n",
            "'plant_params[\"mass_kg\"]' of plant quadcopter"}}) {
    try {
      resolve_scenario(parse_scenario_text(kTwo + text, "s"));
      ADD_FAILURE() << text << " accepted";
    } catch (const ScenarioError& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  }
}

// proto/scenario.proto is the users' reference for every default ("// default 50"); the defaults
// themselves live once, in RunConfig's structs. Every number the schema documents must be what an
// unset field resolves to, so the comment cannot drift from the code.
TEST(Scenario, TheSchemasDocumentedDefaultsAreTheResolvedOnes) {
  std::ifstream in(std::string(QSWARM_SOURCE_DIR) + "/proto/scenario.proto");
  ASSERT_TRUE(in) << "cannot read proto/scenario.proto";
  const RunConfig rc = resolve_scenario(parse_scenario_text(kTwo, "s"));
  const google::protobuf::Descriptor* top = scenario::Scenario::descriptor();
  // The message type each of Scenario's fields holds, by type name: "Rates" -> "rates".
  std::map<std::string, std::string> prefix_of{{"Scenario", ""}};
  for (int i = 0; i < top->field_count(); ++i)
    if (top->field(i)->message_type())
      prefix_of[top->field(i)->message_type()->name()] = top->field(i)->name() + ".";
  const std::regex message_re(R"(^message (\w+) \{)");
  const std::regex field_re(R"(^\s*optional double (\w+) = \d+;\s*//.*\bdefault ([-+0-9.eE]+))");
  std::string line, message;
  int checked = 0;
  std::smatch m;
  while (std::getline(in, line)) {
    if (std::regex_search(line, m, message_re)) message = m[1];
    if (!std::regex_search(line, m, field_re) || !prefix_of.count(message)) continue;
    const std::string path = prefix_of[message] + m[1].str();
    const double documented = std::stod(m[2]);
    // The resolved value, read through the scenario as run (every default is written back).
    const google::protobuf::Message* holder = &rc.resolved;
    std::string rest = path;
    for (auto dot = rest.find('.'); dot != std::string::npos; dot = rest.find('.')) {
      const auto* fd = holder->GetDescriptor()->FindFieldByName(rest.substr(0, dot));
      holder = &holder->GetReflection()->GetMessage(*holder, fd);
      rest = rest.substr(dot + 1);
    }
    const auto* fd = holder->GetDescriptor()->FindFieldByName(rest);
    ASSERT_NE(fd, nullptr) << path;
    EXPECT_TRUE(holder->GetReflection()->HasField(*holder, fd)) << path << " is not written back";
    EXPECT_DOUBLE_EQ(holder->GetReflection()->GetDouble(*holder, fd), documented) << path;
    ++checked;
  }
  EXPECT_GE(checked, 21) << "the schema's defaults were not found: has its comment style changed?";
}

TEST(Scenario, FilesThatAreNotRegularOrTooLargeAreRefusedUnread) {
  for (const std::string path : {"/dev/zero", "/dev/null", "/tmp"}) {
    try {
      read_scenario_file(path);
      ADD_FAILURE() << path << " was read";
    } catch (const ScenarioError& e) {
      EXPECT_NE(std::string(e.what()).find("regular file"), std::string::npos) << e.what();
    }
  }
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("qswarm-scenario-test-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string fifo = (dir / "fifo").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_THROW(read_scenario_file(fifo), ScenarioError);  // never blocks on the open
  const auto big = dir / "big.txtpb";
  {
    std::ofstream out(big);
    const std::string line(1023, '#');
    for (std::size_t i = 0; i <= kMaxScenarioBytes / 1024; ++i) out << line << '\n';
  }
  try {
    read_scenario_file(big.string());
    ADD_FAILURE() << "a file over the limit was read";
  } catch (const ScenarioError& e) {
    EXPECT_NE(std::string(e.what()).find("at most"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_scenario_file((dir / "missing.txtpb").string()), ScenarioError);
  std::filesystem::remove_all(dir);
}

TEST(FaultFlags, ShortcutsNameTheirFlag) {
  scenario::Scenario s;
  const auto why = [&](auto f) -> std::string {
    try {
      f();
    } catch (const ScenarioError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(why([&] {
              add_cut_shortcut(s, "1to2@5:15");
            }).find("--cut '1to2@5:15': expected A-B@START:END"),
            std::string::npos);
  EXPECT_NE(why([&] { add_loss_shortcut(s, 2.0); }).find("--loss"), std::string::npos);
  EXPECT_NE(why([&] { add_loss_shortcut(s, std::nan("")); }).find("--loss"), std::string::npos);
  EXPECT_NE(why([&] { add_kill_shortcut(s, "x@1"); }).find("--kill"), std::string::npos);
  EXPECT_NE(why([&] { add_delay_shortcut(s, "nan"); }).find("--delay"), std::string::npos);
  EXPECT_NE(why([&] { add_partition_shortcut(s, "1,2"); }).find("--partition"), std::string::npos);
  add_cut_shortcut(s, "1-2@5:15");
  ASSERT_EQ(s.faults().cut_size(), 1);
  EXPECT_DOUBLE_EQ(s.faults().cut(0).end_s(), 15.0);
}

}  // namespace
}  // namespace qswarm
