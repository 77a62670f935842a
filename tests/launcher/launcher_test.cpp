// The launcher's policy without processes or waiting: a fake process table and a manual clock.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "common/mcap/writer.hpp"
#include "common/scenario/proto_util.hpp"
#include "common/scenario/scenario.hpp"
#include "launcher/launcher.hpp"

namespace qswarm {
namespace {

// waitpid statuses, as the kernel encodes them.
int exited(int code) { return (code & 0xff) << 8; }
int signalled(int sig) { return sig & 0x7f; }

class FakeProcesses final : public ChildProcesses {
 public:
  pid_t spawn(const std::string& role, unsigned id, const std::vector<std::string>& argv,
              const std::string&, bool) override {
    children_.push_back({role, id, next_pid_, true, 0, false});
    argv_.push_back(argv);
    return next_pid_++;
  }
  std::vector<Child> reap() override {
    std::vector<Child> out;
    out.swap(exited_);
    return out;
  }
  int terminate_all(double) override {
    int killed = 0;
    for (Child& c : children_) {
      if (!c.running) continue;
      c.running = false;
      if (c.role == stubborn_role_ && (c.id == stubborn_ || all_stubborn_)) {
        c.status = signalled(SIGKILL);
        c.killed_at_teardown = true;
        ++killed;
      } else {
        c.status =
            c.role == "agent" && c.id == aborts_at_teardown_ ? signalled(SIGABRT) : exited(0);
      }
    }
    return killed;
  }
  const std::vector<Child>& children() const override { return children_; }

  // The newest process of role/id exits with `status`.
  void exit_child(const std::string& role, unsigned id, int status) {
    for (auto it = children_.rbegin(); it != children_.rend(); ++it) {
      if (it->role == role && it->id == id && it->running) {
        it->running = false;
        it->status = status;
        exited_.push_back(*it);
        return;
      }
    }
    FAIL() << "no running " << role << " " << id;
  }
  int spawned(const std::string& role, unsigned id) const {
    return static_cast<int>(std::count_if(children_.begin(), children_.end(), [&](const Child& c) {
      return c.role == role && c.id == id;
    }));
  }
  std::vector<std::vector<std::string>> argv_;
  unsigned stubborn_ = 0, aborts_at_teardown_ = 0;
  std::string stubborn_role_ = "agent";  // with stubborn_: the child that needs SIGKILL
  bool all_stubborn_ = false;            // every child of stubborn_role_ needs it

 private:
  std::vector<Child> children_, exited_;
  pid_t next_pid_ = 100;
};

LaunchSpec spec_for(const std::string& extra) {
  LaunchSpec spec;
  spec.rc = resolve_scenario(parse_scenario_text(
      "agents { id: 1 }\nagents { id: 2 }\nagents { id: 3 }\nduration_s: 30\n" + extra, "s"));
  // One directory per test and process: ctest runs the tests of this file at once.
  spec.dir = RunDir(std::filesystem::temp_directory_path() /
                    ("qswarm-launcher-test-" +
                     std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) +
                     "-" + std::to_string(::getpid())));
  std::filesystem::create_directories(spec.dir.path());
  spec.bin_dir = "/bin-dir";
  Hosts hosts = spec.rc.plan.hosts;
  hosts.time_scale = 2.0;
  replan(spec.rc, hosts);
  return spec;
}

// The same, with the run's own two Discovery Servers on the block's last ids (supervisor 0,
// agents 1..3).
LaunchSpec spec_with_server() {
  LaunchSpec spec = spec_for("");
  spec.participant_base = 0;
  spec.discovery_ids = {4, 5};
  return spec;
}

// The value after `flag` in argv ("" without it).
std::string arg(const std::vector<std::string>& argv, const std::string& flag) {
  const auto it = std::find(argv.begin(), argv.end(), flag);
  return it == argv.end() || std::next(it) == argv.end() ? std::string() : *std::next(it);
}

bool has(const std::vector<std::string>& argv, const std::string& a) {
  return std::find(argv.begin(), argv.end(), a) != argv.end();
}

TEST(Launcher, StartsNoAgentWhenTheSupervisorNeverListens) {
  FakeProcesses procs;
  ManualClock clock;
  Launcher l(spec_for(""), procs, clock, [] { return false; });
  EXPECT_THROW(l.start(), std::runtime_error);
  EXPECT_GE(clock.now_s(), 20.0);  // waited its 20 s (on the manual clock: instantly)
  EXPECT_EQ(procs.children().size(), 1u);
}

// A supervisor that exits 2 before it listens refused its input (a --view port another program
// took since swarm run looked): the run is refused as bad input, not a failed run, and no agent is
// started.
TEST(Launcher, ASupervisorThatRefusesItsInputRefusesTheRun) {
  FakeProcesses procs;
  ManualClock clock;
  bool refused = false;
  Launcher l(spec_for(""), procs, clock, [&] {
    if (!refused) procs.exit_child("supervisor", 0, exited(2));
    refused = true;
    return false;
  });
  EXPECT_THROW(l.start(), SupervisorRefused);
  EXPECT_EQ(procs.spawned("agent", 1), 0);
  // A supervisor that crashes is not bad input.
  FakeProcesses crashing;
  bool crashed = false;
  Launcher c(spec_for(""), crashing, clock, [&] {
    if (!crashed) crashing.exit_child("supervisor", 0, signalled(SIGSEGV));
    crashed = true;
    return false;
  });
  try {
    c.start();
    ADD_FAILURE() << "a crashed supervisor started a run";
  } catch (const SupervisorRefused&) {
    ADD_FAILURE() << "a crash was taken for bad input";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("did not come up"), std::string::npos) << e.what();
  }
}

TEST(Launcher, ARunsOwnDiscoveryServersStartFirstAndEveryParticipantIsToldTheirAddresses) {
  FakeProcesses procs;
  ManualClock clock;
  LaunchSpec spec = spec_for("transport { domain_id: 3 }");
  spec.participant_base = 10;
  spec.discovery_ids = {14, 15};  // the block's last ids: supervisor 10, agents 11..13
  int polls[2] = {0, 0};
  spec.discovery_ready = [&](int k) { return ++polls[k] > 3 + k; };  // after a few polls each
  Launcher l(spec, procs, clock, [] { return true; });
  l.start();
  ASSERT_EQ(procs.children().size(), 6u);
  EXPECT_EQ(procs.children()[0].role, "discovery");
  EXPECT_EQ(procs.children()[1].role, "discovery");
  EXPECT_EQ(procs.children()[1].id, 1u);
  EXPECT_EQ(procs.children()[2].role, "supervisor");
  // Discovery ports of ids 14 and 15 on domain 3: 7400 + 1100 x 3 + 10 + 2 x id.
  const std::string address = "127.0.0.1:10738,127.0.0.1:10740";
  for (int k = 0; k < 2; ++k) {
    EXPECT_EQ(arg(procs.argv_[k], "--servers"), address);
    EXPECT_EQ(arg(procs.argv_[k], "--index"), std::to_string(k));
    EXPECT_EQ(arg(procs.argv_[k], "--participant-id"), std::to_string(14 + k));
    EXPECT_EQ(arg(procs.argv_[k], "--ready-file"), spec.dir.discovery_ready(k).string());
    EXPECT_FALSE(has(procs.argv_[k], "--test-hang"));
  }
  for (std::size_t i = 2; i < procs.argv_.size(); ++i)
    EXPECT_EQ(arg(procs.argv_[i], "--discovery-server"), address) << procs.children()[i].role;
  // A server a test wants hung is told so.
  spec.hung_servers = {1};
  const Launcher hung(spec, procs, clock, [] { return true; });
  EXPECT_FALSE(has(hung.discovery_argv(0), "--test-hang"));
  EXPECT_TRUE(has(hung.discovery_argv(1), "--test-hang"));
  // The supervisor is found by its role, not its place.
  procs.exit_child("supervisor", 0, exited(0));
  EXPECT_EQ(l.poll(false), std::string(Launcher::kFinished));
}

TEST(Launcher, ASecureRunsProcessesDiscoverByUnicastWithinItsBlockAndAPlainRunsDoNot) {
  LaunchSpec spec = spec_for("");
  spec.rc.transport.keystore = "/ks";  // (the launcher only passes it on)
  replan(spec.rc, spec.rc.plan.hosts);
  spec.participant_base = 10;  // the supervisor 10, agents 1..3 on 11..13
  const auto peers = [](const std::vector<std::string>& argv) {
    const auto it = std::find(argv.begin(), argv.end(), "--unicast-peers");
    return it == argv.end() || it + 1 == argv.end() ? std::string() : *(it + 1);
  };
  FakeProcesses procs;
  ManualClock clock;
  const Launcher secure(spec, procs, clock, [] { return true; });
  EXPECT_EQ(peers(secure.supervisor_argv()), "10:4");
  for (AgentId id : {1u, 2u, 3u}) EXPECT_EQ(peers(secure.agent_argv(id, -1.0, false)), "10:4");
  // Plain: multicast discovery, as Fast DDS does by default.
  spec.rc.transport.keystore.clear();
  replan(spec.rc, spec.rc.plan.hosts);
  const Launcher plain(spec, procs, clock, [] { return true; });
  EXPECT_EQ(peers(plain.supervisor_argv()), "");
  EXPECT_EQ(peers(plain.agent_argv(1, -1.0, false)), "");
  // Secure on every interface (a container's): no block to announce to.
  spec.rc.transport.keystore = "/ks";
  spec.rc.transport.interface = "any";
  const Launcher any(spec, procs, clock, [] { return true; });
  EXPECT_EQ(peers(any.agent_argv(1, -1.0, false)), "");
}

TEST(Launcher, ADiscoveryServerThatNeverListensStartsNothingElse) {
  FakeProcesses procs;
  ManualClock clock;
  LaunchSpec spec = spec_with_server();
  spec.discovery_ready = [](int k) { return k == 0; };  // one of the two listens
  Launcher l(spec, procs, clock, [] { return true; });
  EXPECT_THROW(l.start(), std::runtime_error);
  EXPECT_EQ(procs.children().size(), 2u);  // the servers, and nothing else
}

// The server is up once seen up, and the agents start. When readiness was its ports seen taken,
// the server's own check of them (it binds each briefly) looked like it listening, the next look
// saw them free, and a 256-agent run ended at once "not listening after 20 s".
TEST(Launcher, ADiscoveryServerSeenListeningOnceIsUpAndTheWaitSaysHowLongItTook) {
  FakeProcesses procs;
  ManualClock clock;
  LaunchSpec spec = spec_with_server();
  int polls[2] = {0, 0};
  spec.discovery_ready = [&](int k) { return ++polls[k] == 2; };
  Launcher l(spec, procs, clock, [] { return true; });
  EXPECT_NO_THROW(l.start());
  EXPECT_EQ(procs.children().size(), 6u);  // the servers, the supervisor, agents 1..3
  EXPECT_EQ(polls[0], 2);
  EXPECT_EQ(polls[1], 2);
  // At the plan's priority for it.
  const std::vector<std::string> server = l.discovery_argv(1);
  const auto nice = std::find(server.begin(), server.end(), "--nice");
  ASSERT_NE(nice, server.end());
  ASSERT_NE(std::next(nice), server.end());
  EXPECT_EQ(*std::next(nice), std::to_string(spec.rc.plan.server_nice));

  // One that never listens: the wait says how long it waited (20 s on the manual clock).
  FakeProcesses silent;
  ManualClock clock1;
  spec.discovery_ready = [](int k) { return k == 0; };
  Launcher l1(spec, silent, clock1, [] { return true; });
  try {
    l1.start();
    ADD_FAILURE() << "started without a server";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("Discovery Server 1 did not come up (not listening "
                                         "after 20.0"),
              std::string::npos)
        << e.what();
  }

  // One that dies before it listens: its exit is the reason, after the time it really took.
  FakeProcesses dying;
  ManualClock clock2;
  spec.discovery_ready = [&](int k) {
    if (k == 1 && clock2.now_s() >= 1.0) dying.exit_child("discovery", 1, exited(2));
    return false;
  };
  Launcher l2(spec, dying, clock2, [] { return true; });
  try {
    l2.start();
    ADD_FAILURE() << "started without a server";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("Discovery Server 1 did not come up (exited with code 2"),
              std::string::npos)
        << e.what();
    EXPECT_EQ(std::string(e.what()).find("not listening"), std::string::npos) << e.what();
  }
  EXPECT_LT(clock2.now_s(), 2.0);
  EXPECT_EQ(dying.children().size(), 2u);
}

// One server of two that crashes mid-run, while the other serves to the end (it stops when
// asked: it had not hung), is a note, judged at teardown; with the other lost too, in one pass or
// hung at teardown, no server served and both are problems the record must show.
TEST(Launcher, ADiscoveryServerThatCrashesMidRunIsANoteOnlyWhileTheOtherServesToTheEnd) {
  const LaunchSpec spec = spec_with_server();
  {
    FakeProcesses procs;
    ManualClock clock;
    Launcher l(spec, procs, clock, [] { return true; });
    l.start();
    procs.exit_child("discovery", 0, signalled(SIGSEGV));
    EXPECT_FALSE(l.poll(false));  // the matched participants fly on
    EXPECT_TRUE(l.problems().empty());
    EXPECT_TRUE(l.notes().empty());  // not known yet: the other may have hung
    EXPECT_EQ(l.poll(true), "interrupted");
    l.stop();
    EXPECT_TRUE(l.problems().empty());
    ASSERT_EQ(l.notes().size(), 1u);
    EXPECT_EQ(l.notes()[0].rfind("Discovery Server 0 killed by signal", 0), 0u) << l.notes()[0];
    EXPECT_NE(l.notes()[0].find(" during the run; Discovery Server 1 served to the end"),
              std::string::npos)
        << l.notes()[0];
  }
  for (const bool other_hangs : {false, true}) {
    FakeProcesses procs;
    ManualClock clock;
    Launcher l(spec, procs, clock, [] { return true; });
    l.start();
    procs.exit_child("discovery", 0, exited(1));
    if (!other_hangs) procs.exit_child("discovery", 1, exited(1));  // both in one pass
    EXPECT_FALSE(l.poll(false));
    procs.stubborn_role_ = "discovery";
    procs.stubborn_ = 1;
    EXPECT_EQ(l.poll(true), "interrupted");
    l.stop();
    EXPECT_TRUE(l.notes().empty()) << other_hangs << ": " << l.notes()[0];
    ASSERT_EQ(l.problems().size(), 2u) << other_hangs;
    EXPECT_NE(l.problems()[0].find("Discovery Server 0 exited with code 1 during the run"),
              std::string::npos)
        << l.problems()[0];
    EXPECT_NE(l.problems()[1].find(other_hangs ? "Discovery Server 1 hung"
                                               : "Discovery Server 1 "
                                                 "exited"),
              std::string::npos)
        << l.problems()[1];
  }
}

// A server that dies once it listens, while the supervisor starts, is lost as any other: the
// launcher's waits then read the process table too.
TEST(Launcher, ADiscoveryServerLostWhileTheRunStartsIsJudgedAsAnyOther) {
  FakeProcesses procs;
  ManualClock clock;
  int polls = 0;
  Launcher l(spec_with_server(), procs, clock, [&] {
    if (++polls == 1) procs.exit_child("discovery", 1, signalled(SIGABRT));
    return polls > 2;
  });
  l.start();
  EXPECT_EQ(procs.spawned("agent", 1), 1);  // the other serves: the run goes on
  EXPECT_EQ(l.poll(true), "interrupted");
  l.stop();
  EXPECT_TRUE(l.problems().empty());
  ASSERT_EQ(l.notes().size(), 1u);
  EXPECT_EQ(l.notes()[0].rfind("Discovery Server 1 killed by signal", 0), 0u) << l.notes()[0];
  EXPECT_NE(l.notes()[0].find(" while the run started; Discovery Server 0 served to the end"),
            std::string::npos)
      << l.notes()[0];
}

// A server that needs SIGKILL had hung, and a hung Fast DDS server relays nothing: with the other
// serving to the end the record notes it; with none, peers that were to meet since did not, and
// the run is not "converged".
TEST(Launcher, ADiscoveryServerThatHangsAtTeardownIsANoteOnlyWhileTheOtherRelayed) {
  for (const bool both : {false, true}) {
    FakeProcesses procs;
    ManualClock clock;
    Launcher l(spec_with_server(), procs, clock, [] { return true; });
    l.start();
    procs.stubborn_role_ = "discovery";
    procs.stubborn_ = 1;
    procs.all_stubborn_ = both;
    EXPECT_EQ(l.poll(true), "interrupted");
    EXPECT_EQ(l.stop(), both ? 2 : 1);
    if (!both) {
      EXPECT_TRUE(l.problems().empty());
      ASSERT_EQ(l.notes().size(), 1u);
      EXPECT_EQ(l.notes()[0],
                "Discovery Server 1 hung: it did not stop within 5 s of SIGTERM; Discovery "
                "Server 0 served to the end");
      continue;
    }
    EXPECT_TRUE(l.notes().empty());
    ASSERT_EQ(l.problems().size(), 2u);
    for (int k = 0; k < 2; ++k) {
      const std::string& p = l.problems()[k];
      EXPECT_NE(p.find("Discovery Server " + std::to_string(k) + " hung"), std::string::npos) << p;
      EXPECT_NE(p.find("within 5 s of SIGTERM"), std::string::npos) << p;
      EXPECT_NE(p.find("peers that were to meet after it hung did not"), std::string::npos) << p;
    }
  }
  // The one server of a spec with one is named as before.
  FakeProcesses procs;
  ManualClock clock;
  LaunchSpec one = spec_with_server();
  one.discovery_ids = {4};
  Launcher l(one, procs, clock, [] { return true; });
  l.start();
  procs.stubborn_role_ = "discovery";
  l.poll(true);
  l.stop();
  ASSERT_EQ(l.problems().size(), 1u);
  EXPECT_NE(l.problems()[0].find("the Discovery Server hung"), std::string::npos)
      << l.problems()[0];
}

// What the launcher noted goes into the summary and to the user, and leaves a converged run
// converged (exit 0).
TEST(Launcher, TheSummaryKeepsTheLaunchersNotesAndTheyUnmakeNothing) {
  FakeProcesses procs;
  ManualClock clock;
  const LaunchSpec spec = spec_with_server();
  Launcher l(spec, procs, clock, [] { return true; });
  l.start();
  procs.exit_child("discovery", 1, signalled(SIGKILL));
  EXPECT_FALSE(l.poll(false));
  records::Summary s;
  s.set_converged(true);
  s.set_end_reason("converged");
  ASSERT_TRUE(spec.dir.write_summary(to_json(s)));
  mcap::Writer w;
  ASSERT_TRUE(w.open(spec.dir.mcap()) && w.close());
  procs.exit_child("supervisor", 0, exited(0));
  ASSERT_EQ(l.poll(false), std::string(Launcher::kFinished));
  l.stop();
  for (AgentId id = 1; id <= 3; ++id) std::ofstream(spec.dir.agent_stats(id)) << "{}";
  const Launcher::Outcome out = l.conclude(clock.now_s());
  EXPECT_EQ(out.exit_code, 0);
  ASSERT_FALSE(out.lines.empty());
  EXPECT_EQ(out.lines[0].rfind("Discovery Server 1 killed by signal", 0), 0u) << out.lines[0];
  EXPECT_NE(out.lines[0].find(" during the run; Discovery Server 0 served to the end"),
            std::string::npos)
      << out.lines[0];
  const std::optional<records::Summary> got = spec.dir.read_summary();
  ASSERT_TRUE(got.has_value());
  EXPECT_TRUE(got->converged());
  ASSERT_EQ(got->notes_size(), 1);
  EXPECT_EQ(got->notes(0), out.lines[0]);
  std::filesystem::remove_all(spec.dir.path());
}

TEST(Launcher, AnUnmarkedSigkillIsNotThePlansEvenWithKillsPlanned) {
  FakeProcesses procs;
  ManualClock clock;
  Launcher l(spec_for("faults { kill { agent: 2 at_s: 3 restart_at_s: 6 } }"), procs, clock,
             [] { return true; });
  l.start();
  ASSERT_EQ(procs.children().size(), 4u);  // supervisor + 3 agents
  EXPECT_TRUE(has(procs.argv_[2], "--wait-supervisor"));
  std::filesystem::remove(spec_for("").dir.planned_kills(2));
  // A SIGKILL from outside before the planned one (the agent marked nothing): not the plan's.
  procs.exit_child("agent", 2, signalled(SIGKILL));
  EXPECT_FALSE(l.poll(false));
  EXPECT_EQ(procs.spawned("agent", 2), 1);
  ASSERT_EQ(l.problems().size(), 1u);
  EXPECT_NE(l.problems()[0].find("agent 2"), std::string::npos);
}

TEST(Launcher, RespawnsAMarkedPlannedKillAtItsRestartTime) {
  FakeProcesses procs;
  ManualClock clock;
  const LaunchSpec spec = spec_for("faults { kill { agent: 2 at_s: 3 restart_at_s: 6 } }");
  std::filesystem::remove(spec.dir.planned_kills(2));
  Launcher l(spec, procs, clock, [] { return true; });
  l.start();
  ASSERT_TRUE(spec.dir.mark_planned_kill(2, 3.0));  // what the agent does before dying
  procs.exit_child("agent", 2, signalled(SIGKILL));
  EXPECT_FALSE(l.poll(false));
  ASSERT_EQ(procs.spawned("agent", 2), 2);
  const auto& argv = procs.argv_.back();
  EXPECT_TRUE(has(argv, "--restart"));
  EXPECT_TRUE(has(argv, "6.000000"));  // --join-at the planned restart
  EXPECT_TRUE(l.problems().empty());   // a planned kill is no problem
  // A second SIGKILL is not planned: no respawn, and it is reported.
  procs.exit_child("agent", 2, signalled(SIGKILL));
  EXPECT_FALSE(l.poll(false));
  EXPECT_EQ(procs.spawned("agent", 2), 2);
  ASSERT_EQ(l.problems().size(), 1u);
  EXPECT_NE(l.problems()[0].find("agent 2"), std::string::npos);
}

TEST(Launcher, EndsWithTheSupervisorOnASignalOrAtTheWallLimit) {
  {
    FakeProcesses procs;
    ManualClock clock;
    Launcher l(spec_for(""), procs, clock, [] { return true; });
    l.start();
    procs.exit_child("supervisor", 0, exited(0));
    EXPECT_EQ(l.poll(false), "supervisor finished");
  }
  {
    FakeProcesses procs;
    ManualClock clock;
    Launcher l(spec_for(""), procs, clock, [] { return true; });
    l.start();
    EXPECT_EQ(l.poll(true), "interrupted");
  }
  {
    FakeProcesses procs;
    ManualClock clock;
    Launcher l(spec_for(""), procs, clock, [] { return true; });
    l.start();
    EXPECT_DOUBLE_EQ(l.wall_limit_s(), 30.0 / 2.0 + 120.0);
    clock.advance(134.0);
    EXPECT_FALSE(l.poll(false));
    clock.advance(2.0);
    EXPECT_EQ(l.poll(false), "the supervisor did not finish in time");
  }
}

TEST(Launcher, ACrashAtTeardownIsReportedNotHidden) {
  FakeProcesses procs;
  ManualClock clock;
  Launcher l(spec_for(""), procs, clock, [] { return true; });
  l.start();
  procs.aborts_at_teardown_ = 3;
  procs.stubborn_ = 1;
  EXPECT_EQ(l.poll(true), "interrupted");
  EXPECT_EQ(l.stop(), 1);  // agent 1 needed SIGKILL: escalation, not a crash
  ASSERT_EQ(l.problems().size(), 1u);
  EXPECT_NE(l.problems()[0].find("agent 3"), std::string::npos) << l.problems()[0];
  EXPECT_NE(l.problems()[0].find("teardown"), std::string::npos) << l.problems()[0];
}

TEST(Launcher, AnUnplannedAgentExitEndsTheRunWhenAsked) {
  LaunchSpec spec = spec_for("");
  spec.stop_on_agent_exit = true;
  FakeProcesses procs;
  ManualClock clock;
  Launcher l(spec, procs, clock, [] { return true; });
  l.start();
  procs.exit_child("agent", 3, exited(1));
  EXPECT_EQ(l.poll(false), "agent 3 exited");
  EXPECT_EQ(l.problems().size(), 1u);
}

records::Summary read_summary(const RunDir& dir) {
  const std::optional<records::Summary> s = dir.read_summary();
  EXPECT_TRUE(s.has_value()) << dir.summary() << " does not read as a summary";
  return s.value_or(records::Summary{});
}

// A swarm too large for the machine never gets going and is stopped at the wall limit: the record
// says so, whether the supervisor wrote its summary on the way out or was killed writing it.
TEST(Launcher, ARunStoppedAtTheWallLimitSaysSoAndASummaryCutShortIsReplaced) {
  for (const bool cut_short : {false, true}) {
    FakeProcesses procs;
    ManualClock clock;
    const LaunchSpec spec = spec_for("");
    Launcher l(spec, procs, clock, [] { return true; });
    l.start();
    clock.advance(l.wall_limit_s() + 1.0);
    ASSERT_EQ(l.poll(false), "the supervisor did not finish in time");
    if (cut_short) {
      std::ofstream(spec.dir.summary()).flush();  // 0 bytes: killed while writing
    } else {
      records::Summary s;
      s.set_converged(true);
      s.set_end_reason("interrupted");
      ASSERT_TRUE(spec.dir.write_summary(to_json(s)));
      mcap::Writer w;  // a supervisor that wrote its summary had ended run.mcap first
      ASSERT_TRUE(w.open(spec.dir.mcap()) && w.close());
    }
    l.stop();
    for (AgentId id = 1; id <= 3; ++id) std::ofstream(spec.dir.agent_stats(id)) << "{}";
    const Launcher::Outcome out = l.conclude(clock.now_s());
    EXPECT_EQ(out.exit_code, 1) << cut_short;
    const records::Summary s = read_summary(spec.dir);
    EXPECT_FALSE(s.converged()) << cut_short;
    EXPECT_NE(s.end_reason().find("did not finish in time"), std::string::npos) << s.end_reason();
    EXPECT_FALSE(std::filesystem::exists(spec.dir.summary().string() + ".tmp"));
    std::filesystem::remove_all(spec.dir.path());
  }
}

// What the run was predicted to ask of its host goes into its summary, the supervisor's or the
// one the launcher writes for a supervisor that died.
TEST(Launcher, TheSummaryKeepsThePredictedLoadWhoeverWroteIt) {
  for (const bool supervisor_died : {false, true}) {
    FakeProcesses procs;
    ManualClock clock;
    LaunchSpec spec = spec_for("");
    spec.load.emplace();
    spec.load->set_agents(3);
    spec.load->set_calibrated(true);
    spec.load->set_exceeds(true);
    spec.load->set_predicted_cores(2.5);
    Launcher l(spec, procs, clock, [] { return true; });
    l.start();
    if (!supervisor_died) {
      records::Summary s;
      s.set_converged(false);
      s.set_end_reason("duration");
      ASSERT_TRUE(spec.dir.write_summary(to_json(s)));
      mcap::Writer w;
      ASSERT_TRUE(w.open(spec.dir.mcap()) && w.close());
    }
    procs.exit_child("supervisor", 0, supervisor_died ? signalled(SIGKILL) : exited(1));
    ASSERT_TRUE(l.poll(false).has_value());
    l.stop();
    for (AgentId id = 1; id <= 3; ++id) std::ofstream(spec.dir.agent_stats(id)) << "{}";
    const Launcher::Outcome out = l.conclude(clock.now_s());
    EXPECT_EQ(out.exit_code, 1) << supervisor_died;
    const records::Summary s = read_summary(spec.dir);
    EXPECT_FALSE(s.converged());
    EXPECT_TRUE(s.load().exceeds()) << supervisor_died;
    EXPECT_EQ(s.load().predicted_cores(), 2.5);
    EXPECT_EQ(s.load().agents(), 3U);
    std::filesystem::remove_all(spec.dir.path());
  }
}

// run.mcap ends with a footer only when the supervisor closed it. A summary that says converged
// over a run.mcap cut short (or missing) is amended, and the run exits 3 naming the file; a
// supervisor that died leaves a summary that names it too.
TEST(Launcher, ARunMcapCutShortMakesTheRecordIncompleteNamingIt) {
  for (const bool supervisor_died : {false, true}) {
    FakeProcesses procs;
    ManualClock clock;
    const LaunchSpec spec = spec_for("");
    Launcher l(spec, procs, clock, [] { return true; });
    l.start();
    {
      mcap::Writer w;
      ASSERT_TRUE(w.open(spec.dir.mcap()) && w.close());
    }
    std::filesystem::resize_file(spec.dir.mcap(), 40);  // as a supervisor killed mid-run leaves it
    if (!supervisor_died) {
      records::Summary s;
      s.set_converged(true);
      s.set_end_reason("converged");
      ASSERT_TRUE(spec.dir.write_summary(to_json(s)));
    }
    procs.exit_child("supervisor", 0, supervisor_died ? signalled(SIGKILL) : exited(0));
    ASSERT_TRUE(l.poll(false).has_value());
    l.stop();
    for (AgentId id = 1; id <= 3; ++id) std::ofstream(spec.dir.agent_stats(id)) << "{}";
    const Launcher::Outcome out = l.conclude(clock.now_s());
    EXPECT_EQ(out.exit_code, supervisor_died ? 1 : 3);
    const records::Summary s = read_summary(spec.dir);
    EXPECT_FALSE(s.converged());
    EXPECT_NE(s.end_reason().find("record incomplete: run.mcap: no footer"), std::string::npos)
        << s.end_reason();
    std::string said;
    for (const std::string& line : out.lines) said += line + "\n";
    if (!supervisor_died) {
      EXPECT_NE(said.find("run.mcap"), std::string::npos) << said;
    }
    std::filesystem::remove_all(spec.dir.path());
  }
}

}  // namespace
}  // namespace qswarm
