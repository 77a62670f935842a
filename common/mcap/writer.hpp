#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "common/mcap/records.hpp"

namespace qswarm::mcap {

struct WriterOptions {
  std::string profile;                // the Header's profile ("" : none of the well-known ones)
  std::string library = "quadswarm";  // the Header's library
  // A chunk is written out (at the next message) once it holds this many bytes or its messages span
  // this much log time: a process killed mid-run loses at most the open chunk; viewers seek by it.
  std::uint64_t chunk_bytes = std::uint64_t{512} * 1024;
  std::uint64_t chunk_span_ns = 2'000'000'000;
};

// Writes one MCAP file (https://mcap.dev/spec, major version 0) as it goes: the Header; Schema and
// Channel records as they are added; messages in uncompressed Chunks, each followed by one
// MessageIndex per channel in it; then, on close(), DataEnd with the data section's CRC, a summary
// section (Schema and Channel copies, Statistics, a ChunkIndex per chunk), a SummaryOffset per
// summary group and the Footer with the summary's CRC. Until close() the file has no footer: a
// reader tells a file cut short by its missing trailing magic (see file_check.hpp).
//
// Every write is checked: the first failure (a full disk, a closed descriptor) is kept in error(),
// and the writer then writes nothing more, so the file is never reported whole when it is not.
class Writer {
 public:
  explicit Writer(WriterOptions options = {});
  // Closes the file properly if it is still open (a record is better whole than cut short).
  ~Writer();
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  // Creates (or truncates) the file and writes the magic and the Header. False, with error(), if
  // it cannot.
  bool open(const std::filesystem::path& path);
  // Schema and Channel ids count from 1 in the order they are added.
  std::uint16_t add_schema(std::string_view name, std::string_view encoding, std::string_view data);
  std::uint16_t add_channel(std::uint16_t schema_id, std::string_view topic,
                            std::string_view message_encoding,
                            const std::map<std::string, std::string>& metadata = {});
  // A message at log_time_ns (publish time the same); sequence numbers count per channel from 0.
  // The open chunk, if due (chunk_due()), is written out first.
  bool write(std::uint16_t channel_id, std::uint64_t log_time_ns, std::string_view data);
  // Whether the open chunk holds chunk_bytes or spans chunk_span_ns: the next write() or flush()
  // writes it out.
  bool chunk_due() const;
  // Writes the open chunk out (so that everything so far survives a kill) and flushes.
  bool flush();
  // Writes the rest of the file (chunk, DataEnd, summary, Footer, magic) and closes it. Returns
  // whether the whole file was written; a second call returns the first's result.
  bool close();

  bool ok() const { return error_.empty(); }
  const std::string& error() const { return error_; }
  bool is_open() const { return fd_ >= 0; }
  std::uint64_t message_count() const { return message_count_; }
  std::uint64_t chunk_count() const { return chunk_indexes_.size(); }

 private:
  struct ChannelState {
    std::uint16_t schema_id;
    std::string record;  // the Channel record, for the summary
    std::uint64_t messages = 0;
  };
  struct ChunkIndex {
    std::uint64_t start_ns, end_ns, offset, length;
    std::vector<std::pair<std::uint16_t, std::uint64_t>> index_offsets;
    std::uint64_t index_length, size;
  };

  // Appends to the file, updating the offset and (before DataEnd) the data section's CRC.
  bool emit(std::string_view bytes);
  bool write_chunk();
  void fail(const std::string& what);

  WriterOptions options_;
  std::filesystem::path path_;
  int fd_ = -1;
  bool closed_ = false;
  std::string error_;
  std::uint64_t offset_ = 0;
  std::uint32_t data_crc_ = 0;
  bool in_data_section_ = true;

  std::vector<std::string> schemas_;  // Schema records, by id - 1
  std::vector<ChannelState> channels_;
  std::uint64_t message_count_ = 0;
  std::uint64_t start_ns_ = 0, end_ns_ = 0;

  // The open chunk: its records, their time span, and per channel (log time, offset) pairs.
  std::string chunk_;
  std::uint64_t chunk_start_ns_ = 0, chunk_end_ns_ = 0;
  bool chunk_has_messages_ = false;
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> chunk_index_;
  std::vector<ChunkIndex> chunk_indexes_;
};

}  // namespace qswarm::mcap
