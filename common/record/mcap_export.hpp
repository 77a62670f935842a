#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "common/record/channels.hpp"
#include "common/record/run_dir.hpp"

namespace qswarm {

// A run directory `swarm export` cannot read (missing, not a run's, its scenario unreadable): the
// message names it; the command exits 2.
class ExportError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ExportResult {
  std::uint64_t records = 0;                           // whole records of records.pb exported
  std::array<std::uint64_t, kStreamCount> messages{};  // MCAP messages per stream
  // records.pb did not end on a whole record (a supervisor killed mid-write, a damaged file): where
  // and why, for people. The records before that point were exported.
  std::string partial;
  // The output could not be written completely (a full disk): the file named, and why.
  std::string write_error;
  // `out` was a complete MCAP file and records.pb is damaged: it was kept as it was (why).
  std::string kept;
};

// Rebuilds an MCAP file from a run directory's records.pb (and its scenario.txtpb, for the scene's
// initial average and slots), through the recorder's own sink: from a complete records.pb the file
// is the one the recorder wrote. The file is written beside `out` and renamed over it only once
// complete, so a failed export never leaves a file cut short under that name, and a complete
// `out` is never replaced by an export of damaged records. Throws ExportError when the directory
// is not one it can read (records.pb missing, or not a regular file).
ExportResult export_mcap(const RunDir& dir, const std::filesystem::path& out);

}  // namespace qswarm
