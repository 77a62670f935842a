// What the tests of recorded in-process runs share: a fresh run directory, and the record read
// back.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "common/record/run_dir.hpp"
#include "proto/records.pb.h"

namespace qswarm {

// A fresh run directory per test, tag and process (ctest runs tests at once).
inline RunDir fresh_run_dir(const std::string& tag = "") {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() /
      ("qswarm-in-process-" + std::string(info->name()) + (tag.empty() ? "" : "-" + tag) + "-" +
       std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  return RunDir::claim(dir.string(), "six", "t");
}

inline records::Summary summary_of(const RunDir& dir) {
  const std::optional<records::Summary> s = dir.read_summary();
  EXPECT_TRUE(s.has_value()) << dir.summary() << " does not read as a summary";
  return s.value_or(records::Summary{});
}

// (kind, detail) of every event of events.csv.
inline std::vector<std::pair<std::string, std::string>> events_of(const RunDir& dir) {
  std::ifstream in(dir.events());
  std::vector<std::pair<std::string, std::string>> out;
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    const auto a = line.find(','), b = line.find(',', a + 1), c = line.find(',', b + 1);
    out.emplace_back(line.substr(a + 1, b - a - 1), line.substr(c + 1));
  }
  return out;
}

}  // namespace qswarm
