#include "common/record/record_file.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdint>

#include "common/transport/regular_file.hpp"

namespace qswarm {

namespace fs = std::filesystem;

double record_time_s(const records::Record& r) {
  if (r.has_sample()) return r.sample().stamp_s();
  if (r.has_graph()) return r.graph().t_s();
  if (r.has_event()) return r.event().t_s();
  return 0.0;
}

RecordFileReader::RecordFileReader(const fs::path& path) : path_(path) {
  const RegularFile f = open_regular_file(path, UINTMAX_MAX);
  if (f.problem == RegularFile::Problem::kNotRegular)
    throw RecordFileError(path.string() + ": not a regular file (a run's records are a file)");
  if (f.problem != RegularFile::Problem::kNone)
    throw RecordFileError(path.string() + ": missing or unreadable (" + f.why + ")");
  in_.reset(::fdopen(f.fd, "rb"));
  if (!in_) {
    ::close(f.fd);
    throw RecordFileError(path.string() + ": cannot be read");
  }
}

RecordFileReader::Next RecordFileReader::stop(Next why, const std::string& what, std::uint64_t at) {
  problem_ = path_.filename().string() + ": " + what + " at byte " + std::to_string(at) +
             ", after " + std::to_string(records_) + " whole records";
  return why;
}

RecordFileReader::Next RecordFileReader::next(records::Record& r) {
  if (!problem_.empty()) return Next::kDamaged;
  const std::uint64_t at = at_;
  std::uint64_t len = 0;
  for (int shift = 0;; shift += 7) {
    const int c = std::fgetc(in_.get());
    if (c == EOF) {
      if (shift == 0) return Next::kEnd;
      return stop(Next::kCut, "cut inside a record's length", at);
    }
    ++at_;
    len |= static_cast<std::uint64_t>(c & 0x7f) << shift;
    if (!(c & 0x80)) break;
    if (shift >= 28) return stop(Next::kDamaged, "a record's length is not a 32-bit varint", at);
  }
  if (len > kMaxRecordBytes)
    return stop(Next::kDamaged,
                "a record's length (" + std::to_string(len) + " bytes) is not plausible", at);
  bytes_.resize(len);
  const std::size_t got = std::fread(bytes_.data(), 1, len, in_.get());
  at_ += got;
  if (got != len)
    return stop(Next::kCut,
                "cut inside a record (" + std::to_string(got) + " of its " + std::to_string(len) +
                    " bytes)",
                at);
  if (!r.ParseFromString(bytes_)) return stop(Next::kDamaged, "a record does not parse", at);
  if (!r.has_sample() && !r.has_graph() && !r.has_event())
    return stop(Next::kDamaged, "a record holds nothing (zeros?)", at);
  const double t = record_time_s(r);
  if (!std::isfinite(t) || t < 0.0 || t > kMaxTimeS)
    return stop(Next::kDamaged, "a record's time is not a run's time", at);
  ++records_;
  return Next::kRecord;
}

}  // namespace qswarm
