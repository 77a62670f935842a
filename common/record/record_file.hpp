#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>

#include "proto/records.pb.h"

namespace qswarm {

// A record file that cannot be read at all (missing, not a regular file): the message names it.
class RecordFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The record's time of a record: a sample's stamp, a snapshot's or an event's time.
double record_time_s(const records::Record& r);

// records.pb read back, as RecordSinks writes it: a varint byte count, then the Record; the one
// reader `swarm view` and `swarm export` share. A file a person hands over may be anything: only
// a regular file is opened (a FIFO would block, /dev/zero never end), and the reading stops at the
// first record that is cut short or damaged (a length no record has, bytes that do not parse, a
// record that holds nothing, as zeros read, or a time that is not finite or beyond any run's), so
// that garbage never becomes millions of empty records.
class RecordFileReader {
 public:
  // Throws RecordFileError naming the file when it is missing or not a regular file.
  explicit RecordFileReader(const std::filesystem::path& path);

  enum class Next { kRecord, kEnd, kCut, kDamaged };
  Next next(records::Record& r);
  // Whole records read so far.
  std::uint64_t records() const { return records_; }
  // Where reading stopped and why, for people ("" while it has not): "records.pb: cut inside a
  // record at byte 100, after 3 whole records".
  const std::string& problem() const { return problem_; }

  // Larger than any record the recorder writes (a graph snapshot of 512 agents' complete graph is
  // about 3 MB): a count above it is damage.
  static constexpr std::uint64_t kMaxRecordBytes = 64ull << 20;
  // A record later than this (the longest a scenario may last) is damage.
  static constexpr double kMaxTimeS = 1e7;

 private:
  Next stop(Next why, const std::string& what, std::uint64_t at);
  struct Close {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  std::filesystem::path path_;
  std::unique_ptr<std::FILE, Close> in_;
  std::uint64_t at_ = 0;  // bytes read so far
  std::string bytes_;
  std::uint64_t records_ = 0;
  std::string problem_;
};

}  // namespace qswarm
