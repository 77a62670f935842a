// Every path a person hands the commands, as a careless user or an attacker would: a symlink loop,
// a FIFO, a directory, /dev/zero and a path under a missing directory, in every path flag and the
// scenario's path field. Each command exits 2 naming what it was given (or, where the path is a
// fine one, works), never aborts, never hangs on the FIFO, and leaves the path as it was.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "tests/swarm/domain_lease.hpp"
#include "tests/swarm/harness.hpp"

namespace qswarm {
namespace {

namespace fs = std::filesystem;
using test::bin;

struct Hostile {
  const char* kind;
  fs::path path;
};

// A command with "@" where the hostile path goes, and the exit codes it may end with: 2 unless the
// path is one it may take (an empty or new directory to write a keystore into, say).
struct Case {
  std::vector<std::string> argv;
  std::set<std::string> skip;   // kinds that would make a command fly or are fine inputs
  std::set<std::string> works;  // kinds with which exit 0 is right too
};

TEST(HostilePaths, EveryPathFlagAndFieldRefusesALoopAFifoADirectoryDevZeroAndAMissingParent) {
  const fs::path root = test::fresh_dir("hostile-paths");
  const std::string domain = test::test_domain().str();
  const std::string demo = test::scenario("demo");
  // A recorded run, for the commands that read one.
  const fs::path run = root / "run";
  const test::Result flown =
      test::run({bin("swarm"), "run", demo, "--duration", "2", "--time-scale", "4", "--quiet",
                 "--domain", domain, "--out", run.string()},
                120.0);
  ASSERT_TRUE(flown.code == 0 || flown.code == 1) << flown.output;
  const std::vector<Case> cases = {
      {{bin("swarm"), "run", "@", "--domain", domain}, {}, {}},
      {{bin("swarm"), "run", demo, "--out", "@", "--domain", domain}, {"dir", "missing"}, {}},
      {{bin("swarm"), "run", demo, "--secure", "@", "--domain", domain}, {}, {}},
      {{bin("swarm"), "inspect", "@"}, {}, {}},
      {{bin("swarm"), "keys", "@", "--out", (root / "ks-unused").string()}, {}, {}},
      {{bin("swarm"), "keys", demo, "--out", "@"}, {}, {"dir", "missing"}},
      {{bin("swarm"), "deploy", "k8s", "@", "--out", (root / "deploy-unused").string()}, {}, {}},
      {{bin("swarm"), "deploy", "k8s", demo, "--out", "@"}, {}, {"dir", "missing"}},
      {{bin("swarm"), "export", "--mcap", "@"}, {}, {}},
      {{bin("swarm"), "export", "--mcap", run.string(), "--out", "@"}, {}, {}},
      {{bin("swarm"), "view", "@", "--port", "0"}, {}, {}},
      {{bin("swarm"), "plot", "@"}, {}, {}},
      {{bin("swarm"), "plot", run.string(), "--out", "@"}, {}, {"dir", "missing"}},
      {{bin("swarm"), "paper", "--from", "@"}, {}, {}},
      {{bin("swarm"), "paper", "--scenarios", "@", "--runs", (root / "paper-runs").string()},
       {"dir"},
       {}},
      {{bin("swarm"), "resilience", "@", "--out", (root / "resilience").string()}, {}, {}},
      {{bin("swarm-preview"), "@", "--duration", "0.1"}, {}, {}},
      // Written into /dev/zero, the states vanish as into /dev/null: that works.
      {{bin("swarm-preview"), demo, "--duration", "0.1", "--csv", "@"}, {"missing"}, {"devzero"}},
      {{bin("swarm-agent"), "--scenario", "@", "--id", "1"}, {}, {}},
      {{bin("swarm-agent"), "--scenario", demo, "--id", "1", "--keystore", "@"}, {}, {}},
      {{bin("swarm-agent"), "--scenario", demo, "--id", "1", "--run-dir", "@"}, {"dir"}, {}},
      {{bin("swarm-supervisor"), "--scenario", "@", "--run-dir", run.string()}, {}, {}},
      {{bin("swarm-supervisor"), "--scenario", demo, "--run-dir", "@"}, {"dir"}, {}},
      {{bin("swarm-supervisor"), "--scenario", demo, "--new-run-in", "@"}, {"dir", "missing"}, {}},
  };
  int checked = 0;
  for (const Case& c : cases) {
    for (const char* kind : {"loop", "fifo", "dir", "devzero", "missing"}) {
      if (c.skip.count(kind)) continue;
      // Made anew for each command, so that what one does cannot hide what the next does.
      const fs::path at = root / ("case-" + std::to_string(checked));
      fs::create_directories(at);
      fs::path path = at / "given";
      const std::string k = kind;
      if (k == "loop") fs::create_symlink(path, path);
      if (k == "fifo") ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
      if (k == "dir") fs::create_directories(path);
      if (k == "devzero") fs::create_symlink("/dev/zero", path);
      if (k == "missing") path = at / "no" / "such" / "given";
      std::vector<std::string> argv = c.argv;
      for (std::string& a : argv)
        if (a == "@") a = path.string();
      const test::Result r = test::run(argv, 60.0);
      std::string line;
      for (const std::string& a : argv) line += a + " ";
      ++checked;
      EXPECT_TRUE(r.code == 2 || (r.code == 0 && c.works.count(kind)))
          << kind << ": " << line << "\nexit " << r.code << "\n"
          << r.output;
      if (r.code == 2)
        EXPECT_NE(r.output.find(path.string()), std::string::npos)
            << kind << ": " << line << " did not name it\n"
            << r.output;
      EXPECT_EQ(r.output.find("Traceback"), std::string::npos) << line << r.output;
      EXPECT_EQ(r.output.find("terminate"), std::string::npos) << line << r.output;
      // What it was given is as it was.
      std::error_code ec;
      if (k == "loop") EXPECT_TRUE(fs::is_symlink(path, ec)) << line;
      if (k == "fifo") EXPECT_TRUE(fs::is_fifo(fs::symlink_status(path, ec))) << line;
      if (k == "devzero") EXPECT_EQ(fs::read_symlink(path, ec), "/dev/zero") << line;
      if (k == "dir" && !c.works.count(kind)) EXPECT_TRUE(fs::is_empty(path, ec)) << line;
    }
  }
  EXPECT_GE(checked, 90);
  // The scenario's own path field: transport.keystore.
  for (const char* kind : {"loop", "fifo", "devzero", "missing"}) {
    const fs::path at = root / ("field-" + std::string(kind));
    fs::create_directories(at);
    fs::path ks = at / "keys";
    const std::string k = kind;
    if (k == "loop") fs::create_symlink(ks, ks);
    if (k == "fifo") ASSERT_EQ(::mkfifo(ks.c_str(), 0600), 0);
    if (k == "devzero") fs::create_symlink("/dev/zero", ks);
    if (k == "missing") ks = at / "no" / "keys";
    const fs::path scen = at / "s.txtpb";
    std::ofstream(scen) << test::read_file(demo) << "\ntransport { keystore: \"" << ks.string()
                        << "\" }\n";
    for (const std::vector<std::string>& argv :
         {std::vector<std::string>{bin("swarm"), "inspect", scen.string()},
          std::vector<std::string>{bin("swarm"), "run", scen.string(), "--domain", domain},
          std::vector<std::string>{bin("swarm-preview"), scen.string(), "--duration", "0.1"}}) {
      const test::Result r = test::run(argv, 60.0);
      EXPECT_EQ(r.code, 2) << kind << " " << argv[1] << "\n" << r.output;
      EXPECT_NE(r.output.find("transport.keystore"), std::string::npos) << r.output;
    }
  }
}

}  // namespace
}  // namespace qswarm
