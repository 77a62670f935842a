#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

namespace qswarm::mcap {

// Whether an MCAP file was written to its end. A writer killed or cut short (a SIGKILL, a full
// disk) leaves a file without the Footer and the trailing magic; such a file holds every chunk
// written before that moment, readable from the start by a streaming reader, but no summary, so
// an indexed reader refuses it. A file is complete when it starts and ends with the magic, ends
// with a Footer record, and the Footer's summary CRC (when it is not 0) matches the summary.
struct FileCheck {
  bool complete = false;
  std::string problem;  // why not, for people ("no footer: the file was cut short")
  std::uint64_t bytes = 0;
};
FileCheck check_file(const std::filesystem::path& path);

}  // namespace qswarm::mcap
