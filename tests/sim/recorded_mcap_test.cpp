// run.mcap as the supervisor's recorder writes it during an in-process run (the real
// SupervisorLoop), read back by Foxglove's own reader (tests/mcap/validate.mjs); `swarm export`'s
// rebuild from records.pb; files cut short; a full disk under run.mcap.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "common/mcap/file_check.hpp"
#include "common/record/mcap_export.hpp"
#include "common/scenario/scenario.hpp"
#include "common/sim/in_process_swarm.hpp"
#include "tests/mcap/validate.hpp"
#include "tests/sim/six_agents.hpp"
#include "tests/support/cannot_run.hpp"

namespace qswarm {
namespace {

namespace fs = std::filesystem;
using test::validate_mcap;

fs::path scratch(const std::string& name) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path dir =
      fs::temp_directory_path() /
      ("qswarm-mcap-" + std::string(info->name()) + "-" + std::to_string(::getpid())) / name;
  fs::remove_all(dir);
  return dir;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void write_bytes(const fs::path& p, std::string_view bytes) {
  std::ofstream(p, std::ios::binary | std::ios::trunc)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// A recorded run of the six, with its scenario.txtpb (which `swarm run` writes; export reads it).
RunDir recorded_six() {
  const RunDir dir = RunDir::claim(scratch("run").string(), "six", "t");
  const RunConfig rc = six();
  EXPECT_TRUE(dir.write_scenario(rc.resolved));
  InProcessSwarm swarm(rc, 1.0, dir);
  EXPECT_EQ(swarm.run_recorded(60.0), "converged");
  EXPECT_EQ(swarm.supervisor()->exit_code(), 0);
  return dir;
}

TEST(RecordedMcap, TheRecorderWritesARunMcapFoxglovesReaderOpensWithEveryRecord) {
  QSWARM_REQUIRE_MCAP_VALIDATOR();
  const RunDir dir = recorded_six();
  const mcap::FileCheck c = mcap::check_file(dir.mcap());
  EXPECT_TRUE(c.complete) << c.problem;
  // Both of @mcap/core's readers, every CRC, and the counts per channel against records.pb.
  const test::McapValidation v = validate_mcap(dir.mcap(), dir.records());
  EXPECT_EQ(v.code, 0) << v.output;
  EXPECT_NE(v.output.find("\"schema\":\"qswarm.records.AgentSample\""), std::string::npos)
      << v.output;
  EXPECT_NE(v.output.find("\"schema\":\"foxglove.SceneUpdate\""), std::string::npos) << v.output;
}

TEST(RecordedMcap, ExportRebuildsTheRecordersFileByteForByteFromRecordsPb) {
  QSWARM_REQUIRE_MCAP_VALIDATOR();
  const RunDir dir = recorded_six();
  const fs::path out = scratch("export") / "rebuilt.mcap";
  fs::create_directories(out.parent_path());
  const ExportResult r = export_mcap(dir, out);
  EXPECT_TRUE(r.partial.empty()) << r.partial;
  EXPECT_TRUE(r.write_error.empty()) << r.write_error;
  EXPECT_GT(r.records, 100u);
  EXPECT_EQ(r.messages[static_cast<int>(Stream::kScene)],
            r.messages[static_cast<int>(Stream::kGraph)]);
  EXPECT_TRUE(slurp(out) == slurp(dir.mcap())) << "the export differs from the recorder's file";
  EXPECT_FALSE(fs::exists(out.string() + ".tmp"));
  const test::McapValidation v = validate_mcap(out, dir.records());
  EXPECT_EQ(v.code, 0) << v.output;
}

TEST(RecordedMcap, ARunMcapCutShortIsNotCompleteAndTheIndexedReaderRefusesIt) {
  QSWARM_REQUIRE_MCAP_VALIDATOR();
  const RunDir dir = recorded_six();
  const std::string whole = slurp(dir.mcap());
  // Cut where a killed supervisor leaves it: somewhere in the data section, and just before the
  // trailing magic (the footer written, the magic not).
  for (const std::size_t keep : {whole.size() / 2, whole.size() - 3}) {
    const fs::path cut = scratch("cut") / "run.mcap";
    fs::create_directories(cut.parent_path());
    write_bytes(cut, std::string_view(whole).substr(0, keep));
    const mcap::FileCheck c = mcap::check_file(cut);
    EXPECT_FALSE(c.complete) << keep;
    EXPECT_NE(c.problem.find("cut short"), std::string::npos) << c.problem;
    const test::McapValidation v = validate_mcap(cut, dir.records(), /*truncated=*/true);
    EXPECT_EQ(v.code, 0) << v.output;
  }
}

TEST(RecordedMcap, ARecordsPbCutMidRecordIsExportedUpToItsLastWholeRecordAndSaysSo) {
  QSWARM_REQUIRE_MCAP_VALIDATOR();
  const RunDir run = recorded_six();
  const RunDir dir(scratch("partial"));
  fs::create_directories(dir.path());
  fs::copy_file(run.scenario(), dir.scenario());
  const std::string records = slurp(run.records());
  write_bytes(dir.records(), std::string_view(records).substr(0, records.size() * 2 / 3));
  const ExportResult r = export_mcap(dir, dir.mcap());
  EXPECT_NE(r.partial.find("records.pb: cut inside a record"), std::string::npos) << r.partial;
  EXPECT_NE(r.partial.find("whole records"), std::string::npos) << r.partial;
  EXPECT_TRUE(r.write_error.empty()) << r.write_error;
  EXPECT_TRUE(mcap::check_file(dir.mcap()).complete);
  // Every whole record, no more: the validator counts records.pb's whole records itself.
  const test::McapValidation v = validate_mcap(dir.mcap(), dir.records());
  EXPECT_EQ(v.code, 0) << v.output;
  // Garbage after whole records (a length no record has) is damage, said as such.
  std::size_t whole = 0;  // the end of the first three records
  for (int k = 0; k < 3; ++k) {
    std::size_t len = 0;
    for (int shift = 0;; shift += 7) {
      const auto b = static_cast<std::uint8_t>(records[whole++]);
      len |= static_cast<std::size_t>(b & 0x7f) << shift;
      if (!(b & 0x80)) break;
    }
    whole += len;
  }
  write_bytes(dir.records(), records.substr(0, whole) + std::string(8, '\xff'));
  const ExportResult g = export_mcap(dir, dir.mcap());
  EXPECT_NE(g.partial.find("not a 32-bit varint at byte " + std::to_string(whole)),
            std::string::npos)
      << g.partial;
  EXPECT_EQ(g.records, 3u);
}

// A complete run.mcap is never replaced by an export of damaged records (zeros over the end of
// records.pb): it stays byte for byte, and the result says why.
TEST(RecordedMcap, ACompleteRunMcapIsNeverReplacedByAnExportOfDamagedRecords) {
  const RunDir run = recorded_six();
  ASSERT_TRUE(mcap::check_file(run.mcap()).complete);
  const std::string before = slurp(run.mcap());
  const std::string records = slurp(run.records());
  write_bytes(run.records(), records.substr(0, records.size() / 2) + std::string(4096, '\0'));
  const ExportResult r = export_mcap(run, run.mcap());
  EXPECT_FALSE(r.partial.empty());
  EXPECT_NE(r.kept.find("is complete: kept"), std::string::npos) << r.kept;
  EXPECT_EQ(slurp(run.mcap()), before);
  EXPECT_FALSE(fs::exists(run.mcap().string() + ".tmp"));
  // From whole records it is rebuilt as before.
  write_bytes(run.records(), records);
  const ExportResult whole = export_mcap(run, run.mcap());
  EXPECT_TRUE(whole.partial.empty()) << whole.partial;
  EXPECT_TRUE(whole.kept.empty()) << whole.kept;
  EXPECT_TRUE(mcap::check_file(run.mcap()).complete);
}

TEST(RecordedMcap, ExportRefusesWhatIsNotARunDirectoryNamingIt) {
  const fs::path nowhere = scratch("nowhere");
  EXPECT_THROW(
      {
        try {
          export_mcap(RunDir(nowhere), nowhere / "x.mcap");
        } catch (const ExportError& e) {
          EXPECT_NE(std::string(e.what()).find("not a directory"), std::string::npos) << e.what();
          throw;
        }
      },
      ExportError);
  fs::create_directories(nowhere);
  std::ofstream(nowhere / "notes.txt") << "hello\n";
  try {
    export_mcap(RunDir(nowhere), nowhere / "x.mcap");
    ADD_FAILURE() << "exported a directory without records.pb";
  } catch (const ExportError& e) {
    EXPECT_NE(std::string(e.what()).find("no records.pb"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(nowhere / "x.mcap"));
}

TEST(RecordedMcap, AFullDiskUnderRunMcapEndsTheRunIncompleteNamingItNeverConverged) {
  if (!fs::exists("/dev/full")) QSWARM_CANNOT_RUN("no /dev/full here");
  // Given run.mcap on a device that is always full (every other file of the record is fine)
  const RunDir dir = RunDir::claim(scratch("full").string(), "six", "t");
  fs::create_symlink("/dev/full", dir.mcap());
  InProcessSwarm swarm(six(), 1.0, dir);
  // When the swarm agrees
  EXPECT_EQ(swarm.run_recorded(60.0), "converged");
  // Then the record is incomplete, naming run.mcap, and the summary does not say converged
  EXPECT_EQ(swarm.supervisor()->exit_code(), 3);
  EXPECT_EQ(fs::path(swarm.supervisor()->failed_file()).filename(), "run.mcap");
  const std::optional<records::Summary> s = dir.read_summary();
  ASSERT_TRUE(s.has_value());
  EXPECT_FALSE(s->converged());
  EXPECT_NE(s->end_reason().find("record incomplete: could not write run.mcap"), std::string::npos)
      << s->end_reason();
}

}  // namespace
}  // namespace qswarm
