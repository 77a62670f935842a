// The law seam: every registered law resolves, states its parameters and is checked by them, and
// a sample's payload is checked before any law reads it.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <set>

#include "common/core/law_registry.hpp"
#include "common/core/update_law.hpp"

namespace qswarm {
namespace {

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

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

}  // namespace
}  // namespace qswarm
