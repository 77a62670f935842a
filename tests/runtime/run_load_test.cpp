// A run's predicted load: who hears whom at the start, the host's calibration read back and judged,
// and the costs fitted from calibration runs.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "common/runtime/run_load.hpp"
#include "common/scenario/scenario.hpp"

namespace qswarm {
namespace {

namespace fs = std::filesystem;

RunConfig config(const std::string& text) {
  return resolve_scenario(parse_scenario_text(text, "test"));
}

plan::HostCalibration calibration(double tick_us, double delivery_us) {
  plan::HostCalibration c;
  c.set_host("h");
  c.set_cores(2);
  c.set_measured_at("2026-11-29T00:00:00Z");
  c.set_tick_us_particle(tick_us);
  c.set_tick_us_particle_threads(tick_us);
  c.set_tick_us_quadcopter(4 * tick_us);
  c.set_tick_us_quadcopter_threads(4 * tick_us);
  c.set_delivery_us_tick(delivery_us);
  c.set_delivery_us_threads(2 * delivery_us);
  c.set_quadcopter_steps_per_tick(10);
  return c;
}

// Agents far apart on a fixed ring: each hears its two listed neighbours by name, and nobody by
// place.
std::string far_ring(int n) {
  std::string s = "mode: PARTICLE\nrates { consensus_hz: 50 }\ntopology { policy: FIXED";
  for (int i = 1; i <= n; ++i)
    s += " edges { a: " + std::to_string(i) + " b: " + std::to_string(i % n + 1) + " }";
  s += " }\n";
  for (int i = 1; i <= n; ++i)
    s += "agents { id: " + std::to_string(i) + " position { x: " + std::to_string(1000 * i) +
         " } }\n";
  return s;
}

TEST(RunLoad, EveryoneHearsEveryoneUnderDeliveryAllAndOnlyTheRingOnAFarApartFixedRing) {
  const RunConfig all =
      config("random_agents { count: 5 }\nrates { consensus_hz: 25 }\ntransport { delivery: ALL }");
  const plan::Load a = predict_load(all, 0.5, std::nullopt, 2, "none");
  EXPECT_EQ(a.agents(), 5U);
  EXPECT_DOUBLE_EQ(a.deliveries_per_tick(), 20.0);
  EXPECT_DOUBLE_EQ(a.ticks_per_s(), 5 * 25 * 0.5);
  EXPECT_DOUBLE_EQ(a.deliveries_per_s(), 20 * 25 * 0.5);
  EXPECT_FALSE(a.calibrated());
  EXPECT_EQ(a.calibration(), "none");

  const plan::Load ring = predict_load(config(far_ring(40)), 1.0, std::nullopt, 2, "none");
  EXPECT_DOUBLE_EQ(ring.deliveries_per_tick(), 80.0);  // two neighbours each, not 39
}

TEST(RunLoad, AHostThatSustainsTheRunSaysSoAndOneThatDoesNotNamesTheRateAndScaleThatHold) {
  const RunConfig small = config("random_agents { count: 10 }\ntransport { delivery: ALL }");
  const plan::Load ok = predict_load(small, 1.0, calibration(100, 10), 2, "cal");
  ASSERT_TRUE(ok.calibrated());
  // 500 ticks/s x 100 us + 4500 samples/s x 10 us.
  EXPECT_NEAR(ok.predicted_cores(), 0.05 + 0.045, 1e-12);
  EXPECT_DOUBLE_EQ(ok.usable_cores(), 2 * kUsableCoreShare);
  EXPECT_FALSE(ok.exceeds());
  EXPECT_DOUBLE_EQ(ok.holdable_consensus_hz(), 50.0);
  EXPECT_NEAR(ok.sustained_deliveries_per_s(), (1.5 - 0.05) / 10e-6, 1e-6);
  EXPECT_EQ(load_warning(ok), "");

  const RunConfig big =
      config("random_agents { count: 100 }\ntransport { delivery: ALL receive: TICK }");
  const plan::Load over = predict_load(big, 1.0, calibration(100, 10), 2, "cal");
  EXPECT_NEAR(over.predicted_cores(), 0.5 + 4.95, 1e-9);
  EXPECT_TRUE(over.exceeds());
  // 50 Hz x 1.5 / 5.45 = 13.8 Hz; the fastest whole-hertz rate the 500 Hz physics divides below
  // it: 10 Hz (500 / 37 would be refused as written). Flown at it, the run fits.
  EXPECT_EQ(over.holdable_consensus_hz(), 10.0);
  RunConfig slower = big;
  slower.agent.consensus_hz = over.holdable_consensus_hz();
  EXPECT_FALSE(predict_load(slower, 1.0, calibration(100, 10), 2, "cal").exceeds());
  EXPECT_NEAR(over.holdable_time_scale(), 1.5 / 5.45, 1e-9);
  const std::string w = load_warning(over);
  EXPECT_NE(w.find("exceeds"), std::string::npos) << w;
  EXPECT_NE(describe_load(over).find("EXCEEDS"), std::string::npos);
}

TEST(RunLoad, AQuadcoptersTickCostsItsPhysicsStepsAndThreadsTheirOwnSampleCost) {
  // 50 Hz consensus on 500 Hz physics: the 10 steps a tick it was calibrated at.
  const RunConfig quad = config(
      "mode: QUADCOPTER\nrandom_agents { count: 4 }\ntransport { delivery: ALL receive: TICK }");
  const plan::Load q = predict_load(quad, 1.0, calibration(100, 10), 2, "cal");
  EXPECT_NEAR(q.predicted_cores(), 200 * 400e-6 + 600 * 10e-6, 1e-12);
  // 100 Hz consensus: 5 steps a tick, half the physics.
  const RunConfig fast = config(
      "mode: QUADCOPTER\nrandom_agents { count: 4 }\nrates { consensus_hz: 100 }\n"
      "transport { delivery: ALL receive: THREADS }");
  const plan::Load f = predict_load(fast, 1.0, calibration(100, 10), 2, "cal");
  EXPECT_NEAR(f.predicted_cores(), 400 * 250e-6 + 1200 * 20e-6, 1e-12);
  // 100 quadcopters: their physics alone (100 x 500 steps/s x 30 us) takes the 1.5 cores, so no
  // consensus rate holds, and the prediction says so rather than naming one that does not.
  const RunConfig many = config(
      "mode: QUADCOPTER\nrandom_agents { count: 100 }\ntransport { delivery: ALL receive: TICK }");
  const plan::Load m = predict_load(many, 1.0, calibration(100, 10), 2, "cal");
  ASSERT_TRUE(m.exceeds());
  EXPECT_EQ(m.holdable_consensus_hz(), 0.0);
  EXPECT_NE(load_warning(m).find("no consensus rate"), std::string::npos) << load_warning(m);
}

class CalibrationFile : public ::testing::Test {
 protected:
  fs::path path =
      fs::temp_directory_path() / ("qswarm-calibration-" + std::to_string(::getpid()) + ".txtpb");
  void TearDown() override { fs::remove(path); }
  void write(const std::string& text) { std::ofstream(path) << text; }
};

TEST_F(CalibrationFile, IsReadOnTheHostItWasMeasuredOnAndRefusedNamingWhyElsewhere) {
  std::string why;
  EXPECT_FALSE(read_calibration(path, "h", 2, why));
  EXPECT_NE(why.find("swarm calibrate"), std::string::npos) << why;

  const plan::HostCalibration good = calibration(100, 10);
  write(good.DebugString());
  const auto c = read_calibration(path, "h", 2, why);
  ASSERT_TRUE(c) << why;
  EXPECT_EQ(c->delivery_us_tick(), 10.0);
  EXPECT_FALSE(read_calibration(path, "other", 2, why));
  EXPECT_NE(why.find("not on this host"), std::string::npos) << why;
  EXPECT_FALSE(read_calibration(path, "h", 4, why));
  EXPECT_NE(why.find("4 cores"), std::string::npos) << why;
}

TEST_F(CalibrationFile, ACostThatIsNotAFinitePositiveNumberIsRefusedNamingItsField) {
  for (const double bad : {std::nan(""), 0.0, -1.0, static_cast<double>(INFINITY), 1e9}) {
    plan::HostCalibration c = calibration(100, 10);
    c.set_delivery_us_threads(bad);
    write(c.DebugString());
    std::string why;
    EXPECT_FALSE(read_calibration(path, "h", 2, why)) << bad;
    EXPECT_NE(why.find("'delivery_us_threads'"), std::string::npos) << why;
  }
  write("tick_us_particle: \"fast\"");
  std::string why;
  EXPECT_FALSE(read_calibration(path, "h", 2, why));
  EXPECT_NE(why.find("not a calibration"), std::string::npos) << why;
}

TEST(RunLoad, TwoCalibrationRunsGiveTheCostsBackAndRunsThatCannotTellThemApartGiveNone) {
  // 120 us a tick, 17 us a sample: 4 agents hearing 3, 24 hearing 23.
  const auto sample = [](double ticks, double per_tick) {
    return CalibrationSample{ticks * (120e-6 + per_tick * 17e-6), ticks, ticks * per_tick};
  };
  const auto fit = fit_costs({sample(1600, 3), sample(9600, 23)});
  ASSERT_TRUE(fit);
  EXPECT_NEAR(fit->tick_us, 120.0, 1e-6);
  EXPECT_NEAR(fit->delivery_us, 17.0, 1e-6);
  EXPECT_FALSE(fit_costs({sample(1600, 3), sample(9600, 3)}));  // the same samples a tick
  // More samples costing less: no positive cost per sample.
  EXPECT_FALSE(
      fit_costs({CalibrationSample{1.0, 1600, 4800}, CalibrationSample{1.0, 9600, 220800}}));
  EXPECT_FALSE(fit_costs({CalibrationSample{std::nan(""), 1600, 4800}, sample(9600, 23)}));
}

}  // namespace
}  // namespace qswarm
