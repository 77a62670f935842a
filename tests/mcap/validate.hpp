#pragma once

// Runs tests/mcap/validate.mjs (Foxglove's @mcap/core reader, from node/node_modules, which
// tools/setup.sh installs) on an MCAP file the tests wrote.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "tests/support/cannot_run.hpp"

namespace qswarm::test {

struct McapValidation {
  int code = -1;       // 0: every check passed
  std::string output;  // the validator's JSON line, or why it could not run
};

// Why the validator cannot run here ("" when it can): no node, or packages not installed.
inline std::string mcap_validator_missing() {
  if (std::system("node --version > /dev/null 2>&1") != 0) return "node is not installed";
  if (!std::filesystem::exists(std::filesystem::path(QSWARM_NODE_MODULES) / "@mcap" / "core"))
    return std::string(QSWARM_NODE_MODULES) + "/@mcap/core is missing (tools/setup.sh installs it)";
  return "";
}

// Skips the test where the validator cannot run, except in CI, where it fails: CI's set-up
// installs it, so a missing reader there is a broken set-up, not a machine without it.
#define QSWARM_REQUIRE_MCAP_VALIDATOR()                                                   \
  do {                                                                                    \
    const std::string missing_ = ::qswarm::test::mcap_validator_missing();                \
    if (!missing_.empty()) QSWARM_CANNOT_RUN("cannot validate MCAP files: " << missing_); \
  } while (0)

inline McapValidation validate_mcap(const std::filesystem::path& file,
                                    const std::filesystem::path& records = {},
                                    bool truncated = false) {
  std::string cmd = "node '" + std::string(QSWARM_SOURCE_DIR) +
                    "/tests/mcap/validate.mjs' --modules '" + std::string(QSWARM_NODE_MODULES) +
                    "' '" + file.string() + "'";
  if (!records.empty()) cmd += " --records '" + records.string() + "'";
  if (truncated) cmd += " --truncated";
  cmd += " 2>&1";
  McapValidation v;
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return v;
  char buf[4096];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) v.output.append(buf, n);
  const int status = ::pclose(p);
  v.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return v;
}

}  // namespace qswarm::test
