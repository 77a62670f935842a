// What a run asks of its host, end to end: `swarm calibrate` flies real agent processes and keeps
// what it measured; `swarm inspect` and `swarm run` read it; a run whose predicted load exceeds
// the host says so before it flies and in its summary.
#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "common/runtime/run_load.hpp"
#include "tests/swarm/domain_lease.hpp"
#include "tests/swarm/harness.hpp"

namespace qswarm::test {
namespace {

namespace fs = std::filesystem;

// An environment variable for the children this test starts, as it was after.
class EnvAt {
 public:
  EnvAt(const char* name, const fs::path& value) : name_(name) {
    if (const char* was = getenv(name)) was_ = was;
    setenv(name, value.c_str(), 1);
  }
  ~EnvAt() { was_.empty() ? unsetenv(name_) : setenv(name_, was_.c_str(), 1); }
  EnvAt(const EnvAt&) = delete;
  EnvAt& operator=(const EnvAt&) = delete;

 private:
  const char* name_;
  std::string was_;
};

TEST(Load, ARunBeyondWhatItsHostSustainsSaysSoBeforeItFliesAndInItsSummary) {
  const fs::path dir = fresh_dir("load-exceeds");
  const fs::path cal = dir.parent_path() / "load-exceeds-calibration.txtpb";
  // This host, measured as one where every tick and every sample costs 50 ms of CPU.
  plan::HostCalibration c;
  c.set_host(host_name());
  c.set_cores(host_cores());
  c.set_measured_at("2026-11-29T00:00:00Z");
  using Setter = void (plan::HostCalibration::*)(double);
  for (const Setter set : {&plan::HostCalibration::set_tick_us_particle,
                           &plan::HostCalibration::set_tick_us_quadcopter,
                           &plan::HostCalibration::set_delivery_us_tick,
                           &plan::HostCalibration::set_delivery_us_threads,
                           &plan::HostCalibration::set_tick_us_particle_threads,
                           &plan::HostCalibration::set_tick_us_quadcopter_threads})
    (c.*set)(5e4);
  c.set_quadcopter_steps_per_tick(10);
  std::ofstream(cal) << c.DebugString();
  EnvAt at("QSWARM_CALIBRATION", cal);

  const Result inspect = run({bin("swarm"), "inspect", scenario("paper/time_varying")});
  ASSERT_EQ(inspect.code, 0) << inspect.output;
  EXPECT_NE(inspect.output.find("EXCEEDS this host"), std::string::npos) << inspect.output;

  const Result r = run({bin("swarm"), "run", scenario("paper/time_varying"), "--out", dir.string(),
                        "--domain", test_domain().str(), "--time-scale", "4", "--quiet"},
                       240.0);
  // The prediction does not stop the run: four point agents still meet on this host.
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("swarm run: warning: predicted agent CPU"), std::string::npos)
      << r.output;
  const records::Summary s = read_summary(dir);
  ASSERT_TRUE(s.has_load());
  EXPECT_TRUE(s.load().calibrated());
  EXPECT_TRUE(s.load().exceeds());
  EXPECT_EQ(s.load().agents(), 4U);
  EXPECT_DOUBLE_EQ(s.load().ticks_per_s(), 4 * 50 * 4.0);  // 50 Hz at time scale 4
  EXPECT_GT(s.load().deliveries_per_tick(), 0.0);
  EXPECT_LT(s.load().holdable_time_scale(), 1.0);

  // Calibrated elsewhere: not used, and the record says why.
  c.set_host(host_name() + "-elsewhere");
  std::ofstream(cal) << c.DebugString();
  const Result other = run({bin("swarm"), "inspect", scenario("paper/time_varying"), "--json"});
  ASSERT_EQ(other.code, 0) << other.output;
  records::Inspection ins;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(other.output, &ins).ok());
  EXPECT_FALSE(ins.load().calibrated());
  EXPECT_NE(ins.load().calibration().find("not on this host"), std::string::npos)
      << ins.load().calibration();
  EXPECT_DOUBLE_EQ(ins.load().deliveries_per_tick(), s.load().deliveries_per_tick());
}

TEST(Load, CalibrateFliesRealAgentsAndKeepsCostsThatRunsThenRead) {
  const fs::path cal = fresh_dir("calibrate") / "calibration.txtpb";
  EnvAt at("QSWARM_CALIBRATION", cal);
  // A careless hand: no time to fly, a flight too short, a --keep directory with files in it.
  for (const std::string bad : {"0", "1", "nan"}) {
    const Result r = run({bin("swarm"), "calibrate", "--seconds", bad});
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("--seconds"), std::string::npos) << r.output;
  }
  const Result kept =
      run({bin("swarm"), "calibrate", "--keep", cal.parent_path().parent_path().string()});
  EXPECT_EQ(kept.code, 2) << kept.output;
  EXPECT_NE(kept.output.find("--keep"), std::string::npos) << kept.output;
  EXPECT_FALSE(fs::exists(cal));
  // Kept in a FIFO: refused before flying, and the FIFO left as it was.
  const fs::path fifo = cal.parent_path().parent_path() / "calibrate-fifo";
  fs::remove(fifo);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const Result into_fifo = run({bin("swarm"), "calibrate", "--out", fifo.string()});
  EXPECT_EQ(into_fifo.code, 2) << into_fifo.output;
  EXPECT_NE(into_fifo.output.find("--out"), std::string::npos) << into_fifo.output;
  EXPECT_TRUE(fs::is_fifo(fifo));
  fs::remove(fifo);

  // A TMPDIR that is not there is said, not a crash.
  const fs::path tmp = fresh_dir("calibrate-tmp");
  EnvAt tmpdir("TMPDIR", tmp / "missing");
  const Result no_tmp = run({bin("swarm"), "calibrate", "--domain", test_domain().str()});
  EXPECT_EQ(no_tmp.code, 2) << no_tmp.output;
  EXPECT_NE(no_tmp.output.find("TMPDIR"), std::string::npos) << no_tmp.output;
  EXPECT_FALSE(fs::exists(cal));
  fs::create_directories(tmp);
  setenv("TMPDIR", tmp.c_str(), 1);
  const std::vector<std::string> calibrate = {bin("swarm"), "calibrate", "--seconds",
                                              "2",          "--domain",  test_domain().str()};
  Result r = run(calibrate, 240.0);
  // A host too busy for 2-s flights to tell the costs apart says so (exit 1); once more, longer.
  if (r.code == 1 && r.output.find("do not tell") != std::string::npos) {
    std::vector<std::string> longer = calibrate;
    longer[3] = "6";
    r = run(longer, 240.0);
  }
  ASSERT_EQ(r.code, 0) << r.output;
  std::string why;
  const auto c = read_calibration(cal, host_name(), host_cores(), why);
  ASSERT_TRUE(c) << why << "\n" << r.output;
  // Measured here, now, by the flights it named.
  EXPECT_EQ(c->cores(), host_cores());
  EXPECT_EQ(c->seconds_per_run(), r.output.find("for 6 s") != std::string::npos ? 6.0 : 2.0);
  EXPECT_NE(r.output.find("flying 24 point agents all-to-all"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("flying 4 quadcopters"), std::string::npos) << r.output;
  // Its runs went into a temporary directory of their own, removed after.
  EXPECT_TRUE(fs::is_empty(tmp));

  const Result inspect = run({bin("swarm"), "inspect", scenario("demo"), "--json"});
  ASSERT_EQ(inspect.code, 0) << inspect.output;
  records::Inspection ins;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(inspect.output, &ins).ok());
  EXPECT_TRUE(ins.load().calibrated()) << ins.load().calibration();
  EXPECT_GT(ins.load().predicted_cores(), 0.0);
}

}  // namespace
}  // namespace qswarm::test
