// Where a run's record goes: never over a user's files, never shared by two runs, never outside
// runs/ because of a scenario's name.
#include <gtest/gtest.h>
#include <unistd.h>

#include <google/protobuf/util/json_util.h>

#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include "common/scenario/proto_util.hpp"
#include "proto/records.pb.h"

#include "common/record/run_dir.hpp"

namespace qswarm {
namespace {

namespace fs = std::filesystem;

class RunDirs : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("qswarm-run-dir-" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_);
    old_ = fs::current_path();
    fs::current_path(root_);
  }
  void TearDown() override {
    fs::current_path(old_);
    fs::remove_all(root_);
  }
  fs::path root_, old_;
};

TEST_F(RunDirs, NamesCannotLeaveRunsOrHideAsDotFiles) {
  EXPECT_EQ(safe_name("../../etc/passwd").find('/'), std::string::npos);
  EXPECT_NE(safe_name("../x").front(), '.');
  EXPECT_EQ(safe_name(""), "unnamed");
  EXPECT_EQ(safe_name("paper_time-varying.v2"), "paper_time-varying.v2");
  EXPECT_EQ(safe_name(std::string(300, 'a')).size(), 64u);
  const fs::path dir = RunDir::claim("", "../../escape", "20260101-000000").path();
  EXPECT_EQ(fs::canonical(dir.parent_path()), fs::canonical(root_ / "runs")) << dir;
}

TEST_F(RunDirs, TwoDefaultRunsInTheSameSecondGetTwoDirectories) {
  const fs::path a = RunDir::claim("", "demo", "20260101-000000").path();
  const fs::path b = RunDir::claim("", "demo", "20260101-000000").path();
  EXPECT_NE(a, b);
  EXPECT_TRUE(fs::exists(b / ".swarm-run"));
}

TEST_F(RunDirs, AnOutWithFilesIsRefusedAndOneOutIsClaimedOnce) {
  fs::create_directories("mine");
  std::ofstream("mine/thesis.tex") << "precious";
  try {
    RunDir::claim("mine", "demo", "t").path();
    ADD_FAILURE() << "a directory with files was claimed";
  } catch (const RunDirError& e) {
    EXPECT_NE(std::string(e.what()).find("--out mine"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("thesis.tex"), std::string::npos) << e.what();
  }
  EXPECT_EQ(fs::file_size("mine/thesis.tex"), 8u);  // untouched
  fs::create_directories("empty");
  EXPECT_NO_THROW(RunDir::claim("empty", "demo", "t").path());  // an empty directory is fine
  try {
    RunDir::claim("empty", "demo", "t").path();  // a second run on the same --out
    ADD_FAILURE() << "the same --out was claimed twice";
  } catch (const RunDirError& e) {
    EXPECT_NE(std::string(e.what()).find("another run"), std::string::npos) << e.what();
  }
}

TEST_F(RunDirs, ACrashTheSupervisorCouldNotSeeUnmakesConvergedInTheSummary) {
  RunConfig rc;
  rc.name = "x";
  rc.agents.push_back({1, Vec3::Zero(), 0.0});
  ASSERT_TRUE(RunDir(root_).write_fallback_summary(rc, "converged", 1.0));
  // (write_fallback_summary writes converged: false; make it a converged record first)
  records::Summary s;
  s.set_converged(true);
  s.set_end_reason("converged");
  std::ofstream(root_ / "summary.json") << to_json(s);
  ASSERT_TRUE(RunDir(root_).amend_summary({"agent 3 killed by signal Aborted at teardown"}));
  std::ifstream in(root_ / "summary.json");
  std::stringstream text;
  text << in.rdbuf();
  records::Summary back;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(text.str(), &back).ok());
  EXPECT_FALSE(back.converged());
  EXPECT_EQ(back.end_reason(), "converged; agent 3 killed by signal Aborted at teardown");
}

// The names of a run directory's files in the block "# One run directory." of a script of
// another language (`file`), each a constant matching `constant`: how many it checked.
int check_spelled(const std::string& file, const std::regex& constant) {
  std::ifstream in(std::string(QSWARM_SOURCE_DIR) + "/" + file);
  EXPECT_TRUE(in) << "cannot read " << file;
  std::set<std::string> known;
  for (const RunDir::File& f : RunDir::files()) known.insert(f.name);
  std::string line;
  bool in_block = false;
  int checked = 0;
  std::smatch m;
  while (std::getline(in, line)) {
    if (line == "# One run directory." || line == "// One run directory.") in_block = true;
    if (in_block && line.empty()) break;
    if (!in_block || !std::regex_search(line, m, constant)) continue;
    EXPECT_TRUE(known.count(m[1])) << m[1] << " in " << file << " is not a file RunDir knows";
    ++checked;
  }
  return checked;
}

// The figure scripts spell the run directory's files in python/qswarm/run_dir.py, and the view's
// tests in tests/view/harness.mjs: every name there must be one RunDir writes (or lists), so they
// cannot drift apart.
TEST(RunDirFiles, ThePythonAndTheViewTestsSpellEveryFileAsRunDirDoes) {
  EXPECT_GE(check_spelled("python/qswarm/run_dir.py", std::regex(R"re(^[A-Z_]+ = "([^"]+)")re")), 6)
      << "python/qswarm/run_dir.py's block of run directory names not found";
  EXPECT_GE(check_spelled("tests/view/harness.mjs",
                          std::regex(R"re(^export const [A-Z_]+ = '([^']+)')re")),
            5)
      << "tests/view/harness.mjs's block of run directory names not found";
}

}  // namespace
}  // namespace qswarm
