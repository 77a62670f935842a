#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>

// MCAP's framing (https://mcap.dev/spec): the magic, the record opcodes, and the little-endian
// serialisation every record uses. The writer builds records with it; the file check and the
// tests read them back.
namespace qswarm::mcap {

// 0x89 "MCAP" then the major version '0', "\r\n": at both ends of a file.
inline constexpr std::array<char, 8> kMagic = {'\x89', 'M', 'C', 'A', 'P', '0', '\r', '\n'};

enum class Op : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kAttachment = 0x09,
  kAttachmentIndex = 0x0A,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

// A Footer record: opcode, u64 length 20, summary_start, summary_offset_start, summary_crc.
inline constexpr std::size_t kFooterRecordBytes = 1 + 8 + 8 + 8 + 4;

// Appends MCAP's primitive types to a byte string: fixed-width integers little-endian, a String
// as a u32 byte length and its bytes.
class Bytes {
 public:
  Bytes& u8(std::uint8_t v) {
    out_ += static_cast<char>(v);
    return *this;
  }
  Bytes& u16(std::uint16_t v) { return le(v, 2); }
  Bytes& u32(std::uint32_t v) { return le(v, 4); }
  Bytes& u64(std::uint64_t v) { return le(v, 8); }
  Bytes& str(std::string_view s) {
    u32(static_cast<std::uint32_t>(s.size()));
    return raw(s);
  }
  Bytes& raw(std::string_view s) {
    out_.append(s.data(), s.size());
    return *this;
  }
  const std::string& str() const { return out_; }
  std::string& buffer() { return out_; }
  std::size_t size() const { return out_.size(); }
  void clear() { out_.clear(); }

 private:
  Bytes& le(std::uint64_t v, int n) {
    for (int i = 0; i < n; ++i) out_ += static_cast<char>((v >> (8 * i)) & 0xff);
    return *this;
  }
  std::string out_;
};

// A whole record: opcode, u64 content length, content.
inline std::string record(Op op, std::string_view content) {
  Bytes b;
  b.u8(static_cast<std::uint8_t>(op)).u64(content.size()).raw(content);
  return b.str();
}

// Reads little-endian integers back (for the file check and tests); `at` must leave n bytes.
inline std::uint64_t read_le(std::string_view s, std::size_t at, int n) {
  std::uint64_t v = 0;
  for (int i = n - 1; i >= 0; --i)
    v = (v << 8) | static_cast<std::uint8_t>(s[at + static_cast<std::size_t>(i)]);
  return v;
}

// zlib's CRC-32 of `s`, continuing from `crc` (0 to start).
std::uint32_t crc32(std::string_view s, std::uint32_t crc = 0);

}  // namespace qswarm::mcap
