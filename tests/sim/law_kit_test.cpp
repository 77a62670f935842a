// The conformance kit flies a law through the promises it claims, in the in-process swarm: a law
// that keeps them passes, one that claims what it breaks fails.
#include <gtest/gtest.h>

#include "common/sim/law_kit.hpp"

namespace qswarm {
namespace {

KitOptions repository() {
  KitOptions o;
  o.scenarios = std::string(QSWARM_SOURCE_DIR) + "/scenarios";
  return o;
}

const KitRow& row(const KitReport& r, const std::string& promise, const std::string& flight) {
  for (const KitRow& x : r.rows)
    if (x.promise == promise && x.flight == flight) return x;
  throw std::logic_error("no row " + promise + " / " + flight);
}

TEST(LawKit, EdgeFlowKeepsTheExactAverageUnderEveryFaultAndSaysItDoesNotResistLiars) {
  const KitReport r = check_law(find_law("edge-flow"), repository());
  EXPECT_TRUE(r.passed()) << r.table();
  for (const KitRow& x : r.rows) {
    if (x.promise != "honest hull") {
      EXPECT_TRUE(x.claimed && x.kept) << x.flight << ": " << x.measured;
    } else {
      // It follows a liar: measured and reported, but not a claim it breaks.
      EXPECT_FALSE(x.claimed);
      EXPECT_FALSE(x.kept) << x.flight << ": " << x.measured;
    }
  }
  EXPECT_NE(r.table().find("| edge-flow | exact average | loss 30 % | yes | yes |"),
            std::string::npos)
      << r.table();
}

TEST(LawKit, ALawClaimingTheExactAverageItLosesUnderLossFailsItsKit) {
  // The Laplacian law, as if it claimed what edge-flow keeps: its steps lost on one side only
  // move the swarm's total.
  LawSpec claims_too_much = find_law("laplacian");
  claims_too_much.claims.exact_average = true;
  const KitReport r = check_law(claims_too_much, repository());
  EXPECT_FALSE(r.passed());
  const KitRow& loss = row(r, "exact average", "loss 30 %");
  EXPECT_TRUE(loss.claimed);
  EXPECT_FALSE(loss.kept) << loss.measured;
  EXPECT_NE(r.table().find("**BROKEN**"), std::string::npos) << r.table();
  // Without the claim the same flights pass: the kit judges claims, not laws.
  EXPECT_TRUE(check_law(find_law("laplacian"), repository()).passed());
}

TEST(LawKit, WmsrKeepsTheHonestAgentsInTheirBoxAgainstEachLiar) {
  const KitReport r = check_law(find_law("w-msr"), repository());
  EXPECT_TRUE(r.passed()) << r.table();
  for (const char* attack : {"one liar, constant", "one liar, drift", "one liar, split"})
    EXPECT_TRUE(row(r, "honest hull", attack).kept) << row(r, "honest hull", attack).measured;
}

TEST(LawKit, ParametersAreTheLawsOwnAndChecked) {
  KitOptions o = repository();
  o.params["f"] = 100;
  EXPECT_THROW(check_law(find_law("w-msr"), o), std::exception);
  o = repository();
  o.scenarios = "/nonexistent";
  EXPECT_THROW(check_law(find_law("edge-flow"), o), std::exception);
}

}  // namespace
}  // namespace qswarm
