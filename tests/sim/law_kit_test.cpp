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
  for (const char* attack : {"1 liar, constant", "1 liar, drift", "1 liar, split"})
    EXPECT_TRUE(row(r, "honest hull", attack).kept) << row(r, "honest hull", attack).measured;
}

TEST(LawKit, TheHonestHullIsFlownAgainstTheLawsFLiarsAndClaimedOnlyWhereItHolds) {
  KitOptions o = repository();
  o.params["f"] = 2;  // K7 is (3, 3)-robust: two liars, agents 7 and 6
  KitReport r = check_law(find_law("w-msr"), o);
  EXPECT_TRUE(r.passed()) << r.table();
  EXPECT_TRUE(row(r, "honest hull", "2 liars, drift").claimed);
  EXPECT_TRUE(row(r, "honest hull", "2 liars, drift").kept) << r.table();
  o.params["f"] = 0;  // trims nothing: it follows the one liar, and claims nothing against it
  r = check_law(find_law("w-msr"), o);
  EXPECT_TRUE(r.passed()) << r.table();
  EXPECT_FALSE(row(r, "honest hull", "1 liar, constant").claimed);
  EXPECT_FALSE(row(r, "honest hull", "1 liar, constant").kept);
  o.params["f"] = 4;  // K7 is not (5, 5)-robust: the claim does not apply
  r = check_law(find_law("w-msr"), o);
  EXPECT_FALSE(row(r, "honest hull", "4 liars, split").claimed);
  EXPECT_NE(row(r, "honest hull", "4 liars, split").measured.find("not robust enough"),
            std::string::npos);
}

TEST(LawKit, TheSeparationFlightFindsViolationsWithAvoidanceOff) {
  // The control: the same flight without avoidance brings the quadcopters closer than 1 m.
  KitOptions o = repository();
  o.avoidance = false;
  const KitReport r = check_law(find_law("edge-flow"), o);
  const KitRow& s = row(r, "separation", "paper, unweighted, quadcopters, avoidance off");
  EXPECT_FALSE(s.claimed);
  EXPECT_FALSE(s.kept) << s.measured;
  EXPECT_EQ(s.measured.find(" 0 violations"), std::string::npos) << s.measured;
  EXPECT_TRUE(row(check_law(find_law("edge-flow"), repository()), "separation",
                  "paper, unweighted, quadcopters, avoidance on")
                  .kept);
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
