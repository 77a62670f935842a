// The keystore as a careless user or an attacker would hand it over: a keystore `swarm keys` wrote
// passes, and one with identities swapped, a private key or a directory open to others, a file
// that links out of it, a FIFO, a missing file or another scenario's agents is refused, naming the
// file, and the check writes nothing.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "common/security/keystore.hpp"
#include "tests/swarm/harness.hpp"

namespace qswarm {
namespace {

namespace fs = std::filesystem;

class KeystoreCheck : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = test::fresh_dir("keystore-" + std::to_string(::getpid()) + "-" +
                            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    ks_ = root_ / "keys";
    Keystore::write(ks_, {1, 2, 3}, 2, false);
  }
  void TearDown() override { fs::remove_all(root_); }
  // The check a secure run of agents 1 to 3 makes: "" when it passes, else its message.
  std::string refusal() const {
    try {
      Keystore(ks_).check_run({1, 2, 3});
      return "";
    } catch (const KeystoreError& e) {
      return e.what();
    }
  }
  static int mode_of(const fs::path& p) {
    struct stat st {};
    ::stat(p.c_str(), &st);
    return static_cast<int>(st.st_mode & 07777);
  }
  fs::path root_, ks_;
};

TEST_F(KeystoreCheck, WhatSwarmKeysWritesPassesWithPrivateKeysForTheirOwnersOnly) {
  EXPECT_EQ(refusal(), "");
  for (const char* id : {"agent-1", "agent-2", "agent-3", "supervisor"}) {
    EXPECT_EQ(mode_of(ks_ / id / "key.pem"), 0600) << id;
    EXPECT_EQ(mode_of(ks_ / id), 0700) << id;
  }
  EXPECT_EQ(mode_of(ks_ / "private" / "ca.key.pem"), 0600);
  // Each process checks what it speaks as.
  EXPECT_NO_THROW(Keystore(ks_).check({"agent-2"}));
  EXPECT_NO_THROW(Keystore(ks_).check({Keystore::kSupervisor}));
  // Written once: never over a keystore.
  EXPECT_THROW(Keystore::write(ks_, {1}, 1, false), KeystoreError);
}

TEST_F(KeystoreCheck, SwappedIdentitiesAreRefusedNamingTheCertificate) {
  // Agent 2's and agent 3's certificates and keys swapped: each pair is valid, but each
  // certificate names the other agent.
  for (const char* f : {"cert.pem", "key.pem"}) {
    fs::rename(ks_ / "agent-2" / f, root_ / "tmp");
    fs::rename(ks_ / "agent-3" / f, ks_ / "agent-2" / f);
    fs::rename(root_ / "tmp", ks_ / "agent-3" / f);
  }
  const std::string why = refusal();
  EXPECT_NE(why.find("agent-2/cert.pem: the certificate of agent-3, not of agent-2"),
            std::string::npos)
      << why;
  // The supervisor holding agent 1's identity: refused at its own check, before it flies.
  fs::remove_all(ks_ / "supervisor");
  fs::copy(ks_ / "agent-1", ks_ / "supervisor");
  try {
    Keystore(ks_).check({Keystore::kSupervisor});
    ADD_FAILURE() << "the supervisor flew as agent 1";
  } catch (const KeystoreError& e) {
    EXPECT_NE(std::string(e.what()).find("supervisor/cert.pem: the certificate of agent-1"),
              std::string::npos)
        << e.what();
  }
}

TEST_F(KeystoreCheck, AKeyOrADirectoryOpenToOthersIsRefusedNamingIt) {
  fs::permissions(ks_ / "agent-2" / "key.pem", fs::perms::all);  // 0777
  std::string why = refusal();
  EXPECT_NE(why.find("agent-2/key.pem: a private key readable by others than its owner (mode "
                     "0777)"),
            std::string::npos)
      << why;
  fs::permissions(ks_ / "agent-2" / "key.pem", fs::perms::owner_read | fs::perms::owner_write);
  EXPECT_EQ(refusal(), "");
  fs::permissions(ks_, fs::perms::all);
  why = refusal();
  EXPECT_NE(why.find("writable by others than its owner (mode 0777)"), std::string::npos) << why;
  EXPECT_EQ(why.find(ks_.string() + ":"), 0u) << why;
  fs::permissions(ks_, fs::perms::owner_all | fs::perms::group_read | fs::perms::others_read |
                           fs::perms::group_exec | fs::perms::others_exec);
  fs::permissions(ks_ / "agent-3", fs::perms::owner_all | fs::perms::group_write);
  why = refusal();
  EXPECT_NE(why.find("agent-3: writable by others than its owner (mode 0720)"), std::string::npos)
      << why;
}

TEST_F(KeystoreCheck, ALinkOutOfItAFifoOrAMissingFileIsRefusedNamingIt) {
  // A certificate that links to a copy outside the keystore.
  fs::copy(ks_ / "agent-1" / "cert.pem", root_ / "outside.pem");
  fs::remove(ks_ / "agent-1" / "cert.pem");
  fs::create_symlink(root_ / "outside.pem", ks_ / "agent-1" / "cert.pem");
  std::string why = refusal();
  EXPECT_NE(why.find("agent-1/cert.pem: a link out of the keystore"), std::string::npos) << why;
  // A link inside it is its own business: the same file.
  fs::remove(ks_ / "agent-1" / "cert.pem");
  fs::copy(root_ / "outside.pem", ks_ / "agent-1" / "real.pem");
  fs::create_symlink("real.pem", ks_ / "agent-1" / "cert.pem");
  EXPECT_EQ(refusal(), "");
  // /dev/zero and a FIFO are not a keystore's files, and reading them never blocks.
  fs::remove(ks_ / "agent-1" / "cert.pem");
  fs::create_symlink("/dev/zero", ks_ / "agent-1" / "cert.pem");
  EXPECT_NE(refusal().find("agent-1/cert.pem: not a regular file"), std::string::npos);
  fs::remove(ks_ / "agent-1" / "cert.pem");
  ASSERT_EQ(::mkfifo((ks_ / "agent-1" / "cert.pem").c_str(), 0600), 0);
  EXPECT_NE(refusal().find("agent-1/cert.pem: not a regular file"), std::string::npos);
  // A loop, and a file that is missing.
  fs::remove(ks_ / "agent-1" / "cert.pem");
  fs::create_symlink("cert.pem", ks_ / "agent-1" / "cert.pem");
  EXPECT_NE(refusal().find("agent-1/cert.pem:"), std::string::npos) << refusal();
  fs::remove(ks_ / "agent-1" / "cert.pem");
  EXPECT_NE(refusal().find("agent-1/cert.pem: missing"), std::string::npos) << refusal();
  // The keystore itself a loop: named, never an exception of another kind.
  const fs::path loop = root_ / "loop";
  fs::create_symlink(loop, loop);
  try {
    Keystore(loop).check_run({1});
    ADD_FAILURE() << "a symlink loop passed";
  } catch (const KeystoreError& e) {
    EXPECT_EQ(std::string(e.what()).find(loop.string() + ":"), 0u) << e.what();
  }
}

TEST_F(KeystoreCheck, AnotherScenariosOrAComposeKeystoreIsRefusedForARun) {
  try {
    Keystore(ks_).check_run({1, 2, 3, 4});
    ADD_FAILURE() << "agent 4 has no identity here";
  } catch (const KeystoreError& e) {
    EXPECT_NE(std::string(e.what()).find("agent-4"), std::string::npos) << e.what();
  }
  const fs::path compose = root_ / "compose";
  Keystore::write(compose, {}, 1, true);
  EXPECT_TRUE(Keystore(compose).compose());
  EXPECT_EQ(Keystore(compose).identity_of_agent(7), Keystore::kMember);
  EXPECT_NO_THROW(Keystore(compose).check({Keystore::kMember, Keystore::kSupervisor}));
  try {
    Keystore(compose).check_run({1});
    ADD_FAILURE() << "a compose keystore was taken for a run";
  } catch (const KeystoreError& e) {
    EXPECT_NE(std::string(e.what()).find("a compose keystore"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace qswarm
