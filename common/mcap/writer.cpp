#include "common/mcap/writer.hpp"

#include <fcntl.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace qswarm::mcap {

std::uint32_t crc32(std::string_view s, std::uint32_t crc) {
  // zlib takes lengths as uInt: feed it in pieces that fit.
  while (!s.empty()) {
    const std::size_t n = std::min<std::size_t>(s.size(), 1u << 30);
    crc = static_cast<std::uint32_t>(
        ::crc32(crc, reinterpret_cast<const Bytef*>(s.data()), static_cast<uInt>(n)));
    s.remove_prefix(n);
  }
  return crc;
}

Writer::Writer(WriterOptions options) : options_(std::move(options)) {}

Writer::~Writer() {
  if (is_open()) close();
}

void Writer::fail(const std::string& what) {
  if (error_.empty()) error_ = path_.string() + ": " + what;
}

bool Writer::emit(std::string_view bytes) {
  if (!ok()) return false;
  if (fd_ < 0) {
    fail(closed_ ? "written after close" : "written before open");
    return false;
  }
  if (in_data_section_) data_crc_ = crc32(bytes, data_crc_);
  offset_ += bytes.size();
  while (!bytes.empty()) {
    const ssize_t n = ::write(fd_, bytes.data(), bytes.size());
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      fail(std::string("cannot write (") + (n < 0 ? std::strerror(errno) : "no progress") + ")");
      return false;
    }
    bytes.remove_prefix(static_cast<std::size_t>(n));
  }
  return true;
}

bool Writer::open(const std::filesystem::path& path) {
  path_ = path;
  // Never through a link, and never blocked by a FIFO where the file should be.
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK,
               0644);
  if (fd_ < 0) {
    fail(std::string("cannot create (") + std::strerror(errno) + ")");
    return false;
  }
  Bytes header;
  header.str(options_.profile).str(options_.library);
  return emit({kMagic.data(), kMagic.size()}) && emit(record(Op::kHeader, header.str()));
}

std::uint16_t Writer::add_schema(std::string_view name, std::string_view encoding,
                                 std::string_view data) {
  const auto id = static_cast<std::uint16_t>(schemas_.size() + 1);
  Bytes b;
  b.u16(id).str(name).str(encoding).str(data);  // data: a u32 length-prefixed Bytes, as a String
  schemas_.push_back(record(Op::kSchema, b.str()));
  emit(schemas_.back());
  return id;
}

std::uint16_t Writer::add_channel(std::uint16_t schema_id, std::string_view topic,
                                  std::string_view message_encoding,
                                  const std::map<std::string, std::string>& metadata) {
  const auto id = static_cast<std::uint16_t>(channels_.size() + 1);
  Bytes map;
  for (const auto& [k, v] : metadata) map.str(k).str(v);
  Bytes b;
  b.u16(id).u16(schema_id).str(topic).str(message_encoding).str(map.str());
  channels_.push_back({schema_id, record(Op::kChannel, b.str())});
  emit(channels_.back().record);
  return id;
}

bool Writer::write(std::uint16_t channel_id, std::uint64_t log_time_ns, std::string_view data) {
  if (!ok()) return false;
  if (fd_ < 0) {
    fail(closed_ ? "written after close" : "written before open");
    return false;
  }
  if (channel_id == 0 || channel_id > channels_.size()) {
    fail("message on unknown channel " + std::to_string(channel_id));
    return false;
  }
  // A chunk that became due with the previous message is written out before this one is added:
  // the caller can ask chunk_due() first and put its own files in step with run.mcap.
  if (chunk_due() && !write_chunk()) return false;
  ChannelState& c = channels_[channel_id - 1];
  Bytes m;
  m.u8(static_cast<std::uint8_t>(Op::kMessage)).u64(2 + 4 + 8 + 8 + data.size());
  m.u16(channel_id).u32(static_cast<std::uint32_t>(c.messages)).u64(log_time_ns).u64(log_time_ns);
  m.raw(data);
  if (!chunk_has_messages_) {
    chunk_start_ns_ = chunk_end_ns_ = log_time_ns;
    chunk_has_messages_ = true;
  }
  chunk_start_ns_ = std::min(chunk_start_ns_, log_time_ns);
  chunk_end_ns_ = std::max(chunk_end_ns_, log_time_ns);
  chunk_index_[channel_id].emplace_back(log_time_ns, chunk_.size());
  chunk_ += m.str();
  if (message_count_ == 0) start_ns_ = end_ns_ = log_time_ns;
  start_ns_ = std::min(start_ns_, log_time_ns);
  end_ns_ = std::max(end_ns_, log_time_ns);
  ++message_count_;
  ++c.messages;
  return true;
}

bool Writer::chunk_due() const {
  return chunk_has_messages_ && (chunk_.size() >= options_.chunk_bytes ||
                                 chunk_end_ns_ - chunk_start_ns_ >= options_.chunk_span_ns);
}

bool Writer::write_chunk() {
  if (chunk_.empty()) return ok();
  Bytes c;
  c.u64(chunk_start_ns_).u64(chunk_end_ns_).u64(chunk_.size()).u32(crc32(chunk_)).str("");
  c.u64(chunk_.size()).raw(chunk_);
  ChunkIndex ci{chunk_start_ns_, chunk_end_ns_, offset_, 0, {}, 0, chunk_.size()};
  const std::string chunk = record(Op::kChunk, c.str());
  ci.length = chunk.size();
  bool written = emit(chunk);
  // One MessageIndex per channel in the chunk, in channel order, its entries by log time (messages
  // arrive nearly but not exactly in time order: agents' stamps interleave).
  const std::uint64_t index_start = offset_;
  for (auto& [channel, entries] : chunk_index_) {
    std::stable_sort(entries.begin(), entries.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    Bytes array;
    for (const auto& [t, at] : entries) array.u64(t).u64(at);
    Bytes mi;
    mi.u16(channel).str(array.str());
    ci.index_offsets.emplace_back(channel, offset_);
    written = written && emit(record(Op::kMessageIndex, mi.str()));
  }
  ci.index_length = offset_ - index_start;
  chunk_indexes_.push_back(std::move(ci));
  chunk_.clear();
  chunk_index_.clear();
  chunk_has_messages_ = false;
  return written && ok();
}

bool Writer::flush() {
  if (!ok() || fd_ < 0) return false;
  return write_chunk();
}

bool Writer::close() {
  if (closed_ || fd_ < 0) return closed_ && ok();
  closed_ = true;
  write_chunk();
  Bytes data_end;
  data_end.u32(data_crc_);
  emit(record(Op::kDataEnd, data_end.str()));
  in_data_section_ = false;

  // The summary section, grouped by opcode; Channels before Statistics (the spec asks it).
  const std::uint64_t summary_start = offset_;
  std::string summary;
  struct Group {
    Op op;
    std::uint64_t start, length;
  };
  std::vector<Group> groups;
  const auto group = [&](Op op, const std::vector<std::string>& records) {
    if (records.empty()) return;
    Group g{op, summary_start + summary.size(), 0};
    for (const std::string& r : records) summary += r;
    g.length = summary_start + summary.size() - g.start;
    groups.push_back(g);
  };
  group(Op::kSchema, schemas_);
  std::vector<std::string> channels;
  for (const ChannelState& c : channels_) channels.push_back(c.record);
  group(Op::kChannel, channels);
  Bytes stats;
  stats.u64(message_count_).u16(static_cast<std::uint16_t>(schemas_.size()));
  stats.u32(static_cast<std::uint32_t>(channels_.size())).u32(0).u32(0);
  stats.u32(static_cast<std::uint32_t>(chunk_indexes_.size()));
  stats.u64(message_count_ ? start_ns_ : 0).u64(message_count_ ? end_ns_ : 0);
  Bytes counts;
  for (std::size_t i = 0; i < channels_.size(); ++i)
    counts.u16(static_cast<std::uint16_t>(i + 1)).u64(channels_[i].messages);
  stats.str(counts.str());
  group(Op::kStatistics, {record(Op::kStatistics, stats.str())});
  std::vector<std::string> indexes;
  for (const ChunkIndex& ci : chunk_indexes_) {
    Bytes offsets;
    for (const auto& [channel, at] : ci.index_offsets) offsets.u16(channel).u64(at);
    Bytes b;
    b.u64(ci.start_ns).u64(ci.end_ns).u64(ci.offset).u64(ci.length).str(offsets.str());
    b.u64(ci.index_length).str("").u64(ci.size).u64(ci.size);
    indexes.push_back(record(Op::kChunkIndex, b.str()));
  }
  group(Op::kChunkIndex, indexes);

  const std::uint64_t offsets_start = summary_start + summary.size();
  std::string summary_offsets;
  for (const Group& g : groups) {
    Bytes so;
    so.u8(static_cast<std::uint8_t>(g.op)).u64(g.start).u64(g.length);
    summary_offsets += record(Op::kSummaryOffset, so.str());
  }
  // The Footer's CRC covers the summary, the summary offsets and the Footer up to its CRC field.
  Bytes footer_head;
  footer_head.u8(static_cast<std::uint8_t>(Op::kFooter)).u64(8 + 8 + 4);
  footer_head.u64(summary.empty() ? 0 : summary_start);
  footer_head.u64(summary_offsets.empty() ? 0 : offsets_start);
  std::uint32_t crc = crc32(summary);
  crc = crc32(summary_offsets, crc);
  crc = crc32(footer_head.str(), crc);
  Bytes tail;
  tail.raw(summary).raw(summary_offsets).raw(footer_head.str()).u32(crc);
  tail.raw({kMagic.data(), kMagic.size()});
  emit(tail.str());

  if (::close(fd_) != 0) fail(std::string("cannot close (") + std::strerror(errno) + ")");
  fd_ = -1;
  return ok();
}

}  // namespace qswarm::mcap
