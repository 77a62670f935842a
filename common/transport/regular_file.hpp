#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

namespace qswarm {

// A file a person or another program handed over (a scenario, a keystore's file, a run's record),
// opened for reading only if it is a regular file: opened without blocking, so that a FIFO, even
// one swapped in after a check, cannot hold the process, and judged by what was opened (fstat),
// not by a name that may have changed since.
struct RegularFile {
  enum class Problem { kNone, kMissing, kNotRegular, kTooLarge, kUnreadable };
  Problem problem = Problem::kNone;
  std::string why;  // for people, without the path: "missing", "not a regular file", ...
  int fd = -1;      // open for reading (blocking again) when there is no problem; the caller closes
  std::uintmax_t size = 0;
};
RegularFile open_regular_file(const std::filesystem::path& path, std::uintmax_t max_bytes);

// The whole of a regular file of at most `max_bytes`; "" with `f.problem` set otherwise.
std::string read_regular_file(const std::filesystem::path& path, std::uintmax_t max_bytes,
                              RegularFile& f);

}  // namespace qswarm
