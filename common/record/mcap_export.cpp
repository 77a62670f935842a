#include "common/record/mcap_export.hpp"

#include <optional>

#include "common/mcap/file_check.hpp"
#include "common/record/mcap_sink.hpp"
#include "common/record/record_file.hpp"
#include "common/scenario/scenario.hpp"

namespace qswarm {

namespace fs = std::filesystem;

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
  std::optional<RecordFileReader> in;
  try {
    in.emplace(dir.records());
  } catch (const RecordFileError& e) {
    throw ExportError(e.what());
  }

  ExportResult result;
  const fs::path tmp = out.string() + ".tmp";
  fs::remove(tmp, ec);  // whatever is there (a FIFO, a link) is no file of ours to write through
  McapSink sink(SceneSettings::of(rc));
  if (!sink.open(tmp)) {
    result.write_error = sink.error();
    fs::remove(tmp, ec);
    return result;
  }
  records::Record r;
  for (RecordFileReader::Next got; (got = in->next(r)) != RecordFileReader::Next::kEnd;) {
    if (got != RecordFileReader::Next::kRecord) {
      result.partial = (dir.path() / in->problem()).string();
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
  // A complete file is never replaced by one cut short: from damaged records, only where there was
  // none, or one cut short itself.
  if (!result.partial.empty() && fs::exists(out, ec) && mcap::check_file(out).complete) {
    result.kept = out.string() + " is complete: kept, not replaced by the " +
                  std::to_string(result.records) + " records before the damage";
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
