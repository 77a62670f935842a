// The law seam: every registered law resolves, states its parameters and is checked by them, and
// the example law written only through the seam (metropolis) agrees where it should.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>

#include "common/core/law_registry.hpp"
#include "common/core/update_law.hpp"
#include "common/sim/lockstep_laws.hpp"
#include "tests/core/paper_data.hpp"
#include "tests/support/error_of.hpp"

namespace qswarm {
namespace {

TEST(LawSeam, EveryLawIsFoundByNameAndAliasAndSaysWhatItSends) {
  std::set<std::uint32_t> tags;
  for (const LawSpec& s : registered_laws()) {
    EXPECT_EQ(&find_law(s.name), &s);
    for (const std::string& a : s.aliases) EXPECT_EQ(&find_law(a), &s) << a;
    EXPECT_NE(law_tag(s.name), 0u);
    EXPECT_TRUE(tags.insert(law_tag(s.name)).second) << s.name << ": two laws, one tag";
    EXPECT_LE(s.payload_max, kMaxLawPayload);
    LawConfig cfg;
    cfg.law = s.name;
    const auto law = make_law(3, Vec3(1, 2, 3), cfg);
    const NeighborView v = law->message();
    EXPECT_EQ(v.law, law_tag(s.name));
    EXPECT_LE(v.payload.size(), s.payload_max) << s.name;
  }
  for (const char* shipped : {"edge-flow", "laplacian", "w-msr"})
    EXPECT_EQ(find_law(shipped).name, shipped);
  EXPECT_TRUE(find_law("edge-flow").claims.exact_average);
  EXPECT_TRUE(find_law("w-msr").claims.honest_hull);
  EXPECT_NE(error_of([] { find_law("gossip"); }).find("edge-flow, laplacian, w-msr"),
            std::string::npos);
}

TEST(LawSeam, ParametersAreCheckedByNameAndFilledFromTheirDefaults) {
  const LawSpec& w = find_law("w-msr");
  EXPECT_EQ(resolve_law_params(w, {}).at("f"), 1.0);
  EXPECT_EQ(resolve_law_params(w, {{"f", 3}}).at("f"), 3.0);
  const auto msg = [&](const std::map<std::string, double>& given) {
    return error_of([&] { resolve_law_params(w, given); });
  };
  EXPECT_NE(msg({{"f", 1.5}}).find("law_params[\"f\"]"), std::string::npos);
  EXPECT_NE(msg({{"f", 1.5}}).find("whole number"), std::string::npos);
  EXPECT_NE(msg({{"f", 65}}).find("[0, 64]"), std::string::npos);
  EXPECT_NE(msg({{"f", -1}}).find("got -1"), std::string::npos);
  EXPECT_NE(msg({{"f", std::nan("")}}).find("law_params[\"f\"]"), std::string::npos);
  EXPECT_NE(msg({{"f", std::numeric_limits<double>::infinity()}}).find("got inf"),
            std::string::npos);
  EXPECT_NE(msg({{"step", 0.5}}).find("no such parameter (it takes f)"), std::string::npos);
  EXPECT_NE(error_of([] {
              resolve_law_params(find_law("laplacian"), {{"f", 1}});
            }).find("it takes none"),
            std::string::npos);
  // make_law checks what a LawConfig built in code says, too.
  LawConfig cfg;
  cfg.law = "w-msr";
  cfg.params["f"] = 100;
  EXPECT_NE(error_of([&] { make_law(1, Vec3::Zero(), cfg); }).find("law.params[\"f\"]"),
            std::string::npos);
}

// A law that sends more payload than its LawSpec declares, or NaN in it, would be refused by every
// receiver and fly alone: its own message says so at once.
class Chatty final : public UpdateLaw {
 public:
  Chatty(std::vector<double> payload)
      : UpdateLaw(1, Vec3::Zero(), {}), payload_(std::move(payload)) {}
  Vec3 state() const override { return Vec3::Zero(); }

 private:
  void integrate(const Tick&) override {}
  std::vector<double> payload() const override { return payload_; }
  std::vector<double> payload_;
};

TEST(LawSeam, ALawSendingWhatItsReceiversWouldRefuseFailsAtOnce) {
  EXPECT_NO_THROW(Chatty(std::vector<double>(kMaxLawPayload, 1.0)).message());
  EXPECT_NE(error_of<std::logic_error>([] {
              Chatty(std::vector<double>(kMaxLawPayload + 1, 1.0)).message();
            }).find("more than the 64 its LawSpec declares"),
            std::string::npos);
  EXPECT_NE(error_of<std::logic_error>([] { Chatty({std::nan("")}).message(); }).find("not finite"),
            std::string::npos);
  EXPECT_NE(error_of<std::logic_error>([] { Chatty({2e9}).message(); }).find("beyond 1e9"),
            std::string::npos);
}

TEST(LawSeam, AHostilePayloadNeverPassesTheViewCheck) {
  NeighborView v;
  v.id = 2;
  EXPECT_EQ(check_view(v), "");
  v.payload = {1.0, std::nan("")};
  EXPECT_EQ(check_view(v), "law payload not finite or absurd");
  v.payload = {1e300};
  EXPECT_EQ(check_view(v), "law payload not finite or absurd");
  v.payload.assign(kMaxLawPayload + 1, 0.0);
  EXPECT_EQ(check_view(v), "law payload longer than the wire's bound");
  v.payload.assign(kMaxLawPayload, 0.0);
  EXPECT_EQ(check_view(v), "");
}

LockstepConfig paper_graph_1(const std::string& law) {
  LockstepConfig cfg;
  for (size_t i = 0; i < paper::kUnweightedQ0.size(); ++i)
    cfg.agents.push_back({static_cast<AgentId>(i + 1), paper::kUnweightedQ0[i]});
  cfg.law.law = law;
  cfg.law.weight.policy = WeightPolicy::kUnweighted;
  cfg.law.topology.policy = TopologyPolicy::kFixed;
  cfg.law.topology.edges = paper::kGraph1;
  return cfg;
}

TEST(Metropolis, AgreesAtTheExactAverageOnAFixedGraphInLockstep) {
  LockstepLaws swarm(paper_graph_1("metropolis"));
  ASSERT_TRUE(swarm.run_until_converged(1e-9, 30.0));
  Vec3 avg = Vec3::Zero();
  for (const Vec3& q : paper::kUnweightedQ0) avg += q;
  avg /= static_cast<double>(paper::kUnweightedQ0.size());
  for (const Vec3& q : swarm.states()) EXPECT_LT((q - avg).norm(), 1e-8);
  // Its payload is its degree: agent 2 of the paper's first graph is linked to all three others.
  EXPECT_EQ(swarm.law(1).message().payload, std::vector<double>{3.0});
}

TEST(Metropolis, MovesAFixedShareATickWhateverTheDistances) {
  // Two agents 10 m apart, one link each: weight 1/(1+1) times step 0.5, so in a tick each moves
  // a quarter of the difference toward the other, at any distance and any tick rate.
  LockstepConfig cfg;
  cfg.agents = {{1, Vec3(0, 0, 0)}, {2, Vec3(10, 0, 0)}};
  cfg.law.law = "metropolis";
  cfg.law.topology.policy = TopologyPolicy::kFixed;
  cfg.law.topology.edges = {{1, 2}};
  LockstepLaws swarm(cfg);
  swarm.step();
  EXPECT_NEAR(swarm.states()[0].x(), 2.5, 1e-12);
  EXPECT_NEAR(swarm.states()[1].x(), 7.5, 1e-12);
}

}  // namespace
}  // namespace qswarm
