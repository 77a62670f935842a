#include "common/record/mcap_export.hpp"

#include <fstream>

#include "common/record/mcap_sink.hpp"
#include "common/scenario/scenario.hpp"

namespace qswarm {
namespace {

namespace fs = std::filesystem;

// records.pb's framing: a varint byte count, then the Record. Larger than any record the recorder
// writes (a graph snapshot of 512 agents' complete graph is about 3 MB): a count above it is
// damage.
constexpr std::uint64_t kMaxRecordBytes = 64ull << 20;

enum class Read { kRecord, kEnd, kCut, kDamaged };

Read next_record(std::ifstream& in, std::string& bytes, std::string& why) {
  std::uint64_t len = 0;
  for (int shift = 0;; shift += 7) {
    const int c = in.get();
    if (c == std::char_traits<char>::eof()) {
      if (shift == 0) return Read::kEnd;
      why = "cut inside a record's length";
      return Read::kCut;
    }
    len |= static_cast<std::uint64_t>(c & 0x7f) << shift;
    if (!(c & 0x80)) break;
    if (shift >= 28) {
      why = "a record's length is not a 32-bit varint";
      return Read::kDamaged;
    }
  }
  if (len > kMaxRecordBytes) {
    why = "a record's length (" + std::to_string(len) + " bytes) is not plausible";
    return Read::kDamaged;
  }
  bytes.resize(len);
  in.read(bytes.data(), static_cast<std::streamsize>(len));
  if (static_cast<std::uint64_t>(in.gcount()) != len) {
    why = "cut inside a record (" + std::to_string(in.gcount()) + " of its " + std::to_string(len) +
          " bytes)";
    return Read::kCut;
  }
  return Read::kRecord;
}

}  // namespace

ExportResult export_mcap(const RunDir& dir, const fs::path& out) {
  std::error_code ec;
  if (!fs::is_directory(dir.path(), ec))
    throw ExportError(dir.str() + ": not a directory (a run directory written by swarm run)");
  if (!fs::is_regular_file(dir.records(), ec) || !fs::is_regular_file(dir.scenario(), ec))
    throw ExportError(dir.str() + ": not a run directory (it has no " +
                      (fs::is_regular_file(dir.records(), ec) ? dir.scenario() : dir.records())
                          .filename()
                          .string() +
                      ")");
  RunConfig rc;
  try {
    rc = load_scenario(dir.scenario().string());
  } catch (const ScenarioError& e) {
    throw ExportError(std::string(e.what()));
  }
  std::ifstream in(dir.records(), std::ios::binary);
  if (!in) throw ExportError(dir.records().string() + ": cannot read");

  ExportResult result;
  const fs::path tmp = out.string() + ".tmp";
  McapSink sink(SceneSettings::of(rc));
  if (!sink.open(tmp)) {
    result.write_error = sink.error();
    fs::remove(tmp, ec);
    return result;
  }
  std::string bytes, why;
  records::Record r;
  for (std::uint64_t at = 0;; at = static_cast<std::uint64_t>(in.tellg())) {
    const Read got = next_record(in, bytes, why);
    if (got == Read::kEnd) break;
    if (got == Read::kRecord && !r.ParseFromString(bytes)) why = "a record does not parse";
    if (got != Read::kRecord || !why.empty()) {
      result.partial = dir.records().string() + ": " + why + " at byte " + std::to_string(at) +
                       ", after " + std::to_string(result.records) + " whole records";
      break;
    }
    sink.write(r);
    ++result.records;
  }
  const bool written = sink.close();
  result.messages = sink.counts();
  if (!written) {
    result.write_error = sink.error();
    fs::remove(tmp, ec);
    return result;
  }
  fs::rename(tmp, out, ec);
  if (ec) {
    result.write_error = out.string() + ": cannot write (" + ec.message() + ")";
    fs::remove(tmp, ec);
  }
  return result;
}

}  // namespace qswarm
