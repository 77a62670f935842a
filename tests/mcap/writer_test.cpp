// The MCAP writer against the specification (https://mcap.dev/spec), byte by byte: records are
// read back here by a walker that knows only the spec's framing, and CRCs are zlib's own.
#include <gtest/gtest.h>
#include <zlib.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "common/mcap/file_check.hpp"
#include "common/mcap/writer.hpp"
#include "tests/support/cannot_run.hpp"

namespace qswarm::mcap {
namespace {

namespace fs = std::filesystem;

std::uint32_t zlib_crc(std::string_view s) {
  return static_cast<std::uint32_t>(
      ::crc32(0, reinterpret_cast<const Bytef*>(s.data()), static_cast<uInt>(s.size())));
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

fs::path temp_file(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("qswarm-mcap-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

// Reads a record's fields in order, as the spec lists them.
struct Fields {
  std::string_view s;
  std::size_t at = 0;
  std::uint64_t u(int n) {
    const std::uint64_t v = read_le(s, at, n);
    at += static_cast<std::size_t>(n);
    return v;
  }
  std::string_view str() {
    const auto n = static_cast<std::size_t>(u(4));
    const std::string_view v = s.substr(at, n);
    at += n;
    return v;
  }
  std::string_view bytes(std::size_t n) {
    const std::string_view v = s.substr(at, n);
    at += n;
    return v;
  }
  bool done() const { return at == s.size(); }
};

struct Record {
  Op op;
  std::uint64_t offset;  // of its opcode, in the file (or the chunk)
  std::uint64_t length;  // opcode + length + content
  std::string_view content;
};

// The records between two offsets (the file's after its magic, or a chunk's).
std::vector<Record> walk(std::string_view s, std::size_t from, std::size_t to) {
  std::vector<Record> out;
  std::size_t at = from;
  while (at < to) {
    EXPECT_LE(at + 9, to);
    if (at + 9 > to) break;
    const auto op = static_cast<Op>(static_cast<std::uint8_t>(s[at]));
    const std::uint64_t len = read_le(s, at + 1, 8);
    EXPECT_LE(at + 9 + len, to) << "record at " << at << " runs past its section";
    if (at + 9 + len > to) break;
    out.push_back({op, at, 9 + len, s.substr(at + 9, len)});
    at += 9 + len;
  }
  return out;
}

std::vector<Op> ops(const std::vector<Record>& rs) {
  std::vector<Op> v;
  for (const Record& r : rs) v.push_back(r.op);
  return v;
}

const std::string_view kMagicView(kMagic.data(), kMagic.size());

TEST(McapWriter, AnEmptyFileIsMagicHeaderDataEndStatisticsFooterMagic) {
  const fs::path path = temp_file("empty.mcap");
  {
    Writer w({"", "quadswarm-test"});
    ASSERT_TRUE(w.open(path)) << w.error();
    ASSERT_TRUE(w.close()) << w.error();
  }
  const std::string f = slurp(path);
  ASSERT_GE(f.size(), 16u);
  EXPECT_EQ(f.substr(0, 8), kMagicView);
  EXPECT_EQ(f.substr(f.size() - 8), kMagicView);
  EXPECT_EQ(static_cast<std::uint8_t>(f[8]), 0x01);  // Header
  const auto rs = walk(f, 8, f.size() - 8);
  ASSERT_EQ(ops(rs), (std::vector<Op>{Op::kHeader, Op::kDataEnd, Op::kStatistics,
                                      Op::kSummaryOffset, Op::kFooter}));
  Fields header{rs[0].content};
  EXPECT_EQ(header.str(), "");
  EXPECT_EQ(header.str(), "quadswarm-test");
  EXPECT_TRUE(header.done());
  // DataEnd: the CRC of every byte before it, the leading magic included.
  Fields data_end{rs[1].content};
  EXPECT_EQ(data_end.u(4), zlib_crc(std::string_view(f).substr(0, rs[1].offset)));
  Fields stats{rs[2].content};
  EXPECT_EQ(stats.u(8), 0u);  // messages
  EXPECT_EQ(stats.u(2), 0u);  // schemas
  EXPECT_EQ(stats.u(4), 0u);  // channels
  EXPECT_EQ(stats.u(4), 0u);  // attachments
  EXPECT_EQ(stats.u(4), 0u);  // metadata
  EXPECT_EQ(stats.u(4), 0u);  // chunks
  EXPECT_EQ(stats.u(8), 0u);  // start: zero without messages
  EXPECT_EQ(stats.u(8), 0u);  // end
  EXPECT_EQ(stats.str(), "");
  EXPECT_TRUE(stats.done());
  Fields footer{rs[4].content};
  EXPECT_EQ(rs[4].length, kFooterRecordBytes);
  EXPECT_EQ(footer.u(8), rs[2].offset);  // summary_start
  EXPECT_EQ(footer.u(8), rs[3].offset);  // summary_offset_start
  const std::string_view covered =
      std::string_view(f).substr(rs[2].offset, rs[4].offset + 25 - rs[2].offset);
  EXPECT_EQ(footer.u(4), zlib_crc(covered));
  EXPECT_TRUE(check_file(path).complete) << check_file(path).problem;
}

TEST(McapWriter, MessagesGoInAChunkWithAnIndexPerChannelAndTheSummaryPointsAtThem) {
  const fs::path path = temp_file("two.mcap");
  Writer w({"", "quadswarm-test"});
  ASSERT_TRUE(w.open(path));
  const std::uint16_t s1 = w.add_schema("pkg.A", "protobuf", std::string("\x0a\x00\xff", 3));
  const std::uint16_t s2 = w.add_schema("pkg.B", "jsonschema", "{}");
  const std::uint16_t c1 = w.add_channel(s1, "/a", "protobuf", {{"k", "v"}});
  const std::uint16_t c2 = w.add_channel(s2, "/b", "json");
  EXPECT_EQ(s1, 1);
  EXPECT_EQ(s2, 2);
  EXPECT_EQ(c1, 1);
  EXPECT_EQ(c2, 2);
  ASSERT_TRUE(w.write(c1, 2000, "first"));
  ASSERT_TRUE(w.write(c2, 1500, "{\"x\":1}"));
  ASSERT_TRUE(w.write(c1, 1000, "earlier"));  // out of order, as agents' stamps interleave
  ASSERT_TRUE(w.close()) << w.error();
  EXPECT_EQ(w.message_count(), 3u);

  const std::string f = slurp(path);
  const std::string_view fv(f);
  const auto rs = walk(f, 8, f.size() - 8);
  ASSERT_EQ(ops(rs),
            (std::vector<Op>{
                Op::kHeader,        Op::kSchema,        Op::kSchema,        Op::kChannel,
                Op::kChannel,       Op::kChunk,         Op::kMessageIndex,  Op::kMessageIndex,
                Op::kDataEnd,       Op::kSchema,        Op::kSchema,        Op::kChannel,
                Op::kChannel,       Op::kStatistics,    Op::kChunkIndex,    Op::kSummaryOffset,
                Op::kSummaryOffset, Op::kSummaryOffset, Op::kSummaryOffset, Op::kFooter}));
  Fields schema{rs[1].content};
  EXPECT_EQ(schema.u(2), 1u);
  EXPECT_EQ(schema.str(), "pkg.A");
  EXPECT_EQ(schema.str(), "protobuf");
  EXPECT_EQ(schema.str(), std::string_view("\x0a\x00\xff", 3));  // binary data, length-prefixed
  EXPECT_TRUE(schema.done());
  Fields channel{rs[3].content};
  EXPECT_EQ(channel.u(2), 1u);
  EXPECT_EQ(channel.u(2), 1u);  // schema id
  EXPECT_EQ(channel.str(), "/a");
  EXPECT_EQ(channel.str(), "protobuf");
  Fields map{channel.str()};
  EXPECT_EQ(map.str(), "k");
  EXPECT_EQ(map.str(), "v");
  EXPECT_TRUE(map.done());
  EXPECT_TRUE(channel.done());

  // The chunk: its time span, its records' size and CRC, no compression, three messages.
  Fields chunk{rs[5].content};
  EXPECT_EQ(chunk.u(8), 1000u);
  EXPECT_EQ(chunk.u(8), 2000u);
  const std::uint64_t size = chunk.u(8);
  const auto crc = static_cast<std::uint32_t>(chunk.u(4));
  EXPECT_EQ(chunk.str(), "");
  EXPECT_EQ(chunk.u(8), size);
  const std::string_view records = chunk.bytes(static_cast<std::size_t>(size));
  EXPECT_TRUE(chunk.done());
  EXPECT_EQ(crc, zlib_crc(records));
  const auto inner = walk(records, 0, records.size());
  ASSERT_EQ(ops(inner), (std::vector<Op>{Op::kMessage, Op::kMessage, Op::kMessage}));
  Fields m3{inner[2].content};
  EXPECT_EQ(m3.u(2), 1u);     // channel
  EXPECT_EQ(m3.u(4), 1u);     // its second message on channel 1
  EXPECT_EQ(m3.u(8), 1000u);  // log time
  EXPECT_EQ(m3.u(8), 1000u);  // publish time: the log time
  EXPECT_EQ(m3.bytes(7), "earlier");
  EXPECT_TRUE(m3.done());

  // Message indexes: channel 1's by log time, offsets into the uncompressed records.
  Fields mi1{rs[6].content};
  EXPECT_EQ(mi1.u(2), 1u);
  Fields entries{mi1.str()};
  EXPECT_EQ(entries.u(8), 1000u);
  EXPECT_EQ(entries.u(8), inner[2].offset);
  EXPECT_EQ(entries.u(8), 2000u);
  EXPECT_EQ(entries.u(8), inner[0].offset);
  EXPECT_TRUE(entries.done());
  Fields mi2{rs[7].content};
  EXPECT_EQ(mi2.u(2), 2u);

  Fields data_end{rs[8].content};
  EXPECT_EQ(data_end.u(4), zlib_crc(fv.substr(0, rs[8].offset)));
  EXPECT_EQ(rs[9].content, rs[1].content);   // the summary's Schema copies
  EXPECT_EQ(rs[11].content, rs[3].content);  // and Channel copies

  Fields stats{rs[13].content};
  EXPECT_EQ(stats.u(8), 3u);
  EXPECT_EQ(stats.u(2), 2u);
  EXPECT_EQ(stats.u(4), 2u);
  stats.u(4);
  stats.u(4);
  EXPECT_EQ(stats.u(4), 1u);  // chunks
  EXPECT_EQ(stats.u(8), 1000u);
  EXPECT_EQ(stats.u(8), 2000u);
  Fields counts{stats.str()};
  std::map<std::uint64_t, std::uint64_t> per_channel;
  while (!counts.done()) {
    const std::uint64_t id = counts.u(2);
    per_channel[id] = counts.u(8);
  }
  EXPECT_EQ(per_channel, (std::map<std::uint64_t, std::uint64_t>{{1, 2}, {2, 1}}));

  Fields ci{rs[14].content};
  EXPECT_EQ(ci.u(8), 1000u);
  EXPECT_EQ(ci.u(8), 2000u);
  EXPECT_EQ(ci.u(8), rs[5].offset);
  EXPECT_EQ(ci.u(8), rs[5].length);
  Fields offsets{ci.str()};
  EXPECT_EQ(offsets.u(2), 1u);
  EXPECT_EQ(offsets.u(8), rs[6].offset);
  EXPECT_EQ(offsets.u(2), 2u);
  EXPECT_EQ(offsets.u(8), rs[7].offset);
  EXPECT_TRUE(offsets.done());
  EXPECT_EQ(ci.u(8), rs[6].length + rs[7].length);
  EXPECT_EQ(ci.str(), "");
  EXPECT_EQ(ci.u(8), size);  // compressed size: uncompressed, the same
  EXPECT_EQ(ci.u(8), size);
  EXPECT_TRUE(ci.done());

  // One SummaryOffset per group, pointing at it.
  const std::vector<std::pair<Op, std::pair<std::size_t, std::size_t>>> groups = {
      {Op::kSchema, {9, 10}},
      {Op::kChannel, {11, 12}},
      {Op::kStatistics, {13, 13}},
      {Op::kChunkIndex, {14, 14}}};
  for (std::size_t g = 0; g < groups.size(); ++g) {
    Fields so{rs[15 + g].content};
    EXPECT_EQ(so.u(1), static_cast<std::uint64_t>(groups[g].first));
    const auto [first, last] = groups[g].second;
    EXPECT_EQ(so.u(8), rs[first].offset);
    EXPECT_EQ(so.u(8), rs[last].offset + rs[last].length - rs[first].offset);
  }
  Fields footer{rs[19].content};
  EXPECT_EQ(footer.u(8), rs[9].offset);
  EXPECT_EQ(footer.u(8), rs[15].offset);
  EXPECT_EQ(footer.u(4), zlib_crc(fv.substr(rs[9].offset, rs[19].offset + 25 - rs[9].offset)));
}

TEST(McapWriter, AChunkClosesOnceItSpansTheTimeOrHoldsTheBytesAndOnFlush) {
  const fs::path path = temp_file("chunks.mcap");
  Writer w({"", "t", /*chunk_bytes=*/200, /*chunk_span_ns=*/1000});
  ASSERT_TRUE(w.open(path));
  const std::uint16_t c = w.add_channel(0, "/x", "json");  // no schema: id 0
  w.write(c, 0, "a");
  w.write(c, 999, "b");
  EXPECT_EQ(w.chunk_count(), 0u);
  EXPECT_FALSE(w.chunk_due());
  w.write(c, 1000, "c");  // spans 1000 ns: due, written out with the next message
  EXPECT_TRUE(w.chunk_due());
  EXPECT_EQ(w.chunk_count(), 0u);
  w.write(c, 1001, std::string(250, 'x'));  // holds 200 bytes: due
  EXPECT_EQ(w.chunk_count(), 1u);
  EXPECT_TRUE(w.chunk_due());
  w.write(c, 1002, "d");
  EXPECT_EQ(w.chunk_count(), 2u);
  EXPECT_FALSE(w.chunk_due());
  ASSERT_TRUE(w.flush());
  EXPECT_EQ(w.chunk_count(), 3u);
  ASSERT_TRUE(w.flush());  // nothing open: no empty chunk
  EXPECT_EQ(w.chunk_count(), 3u);
  ASSERT_TRUE(w.close());
  EXPECT_TRUE(check_file(path).complete);
}

TEST(McapWriter, AFullDiskIsAnErrorThatNamesTheFileAndStopsTheWriter) {
  if (!fs::exists("/dev/full")) QSWARM_CANNOT_RUN("no /dev/full on this machine");
  Writer w;
  ASSERT_FALSE(w.open("/dev/full") && w.flush() && w.close());
  EXPECT_FALSE(w.ok());
  EXPECT_NE(w.error().find("/dev/full"), std::string::npos) << w.error();
  EXPECT_NE(w.error().find("No space left"), std::string::npos) << w.error();
  EXPECT_FALSE(w.write(1, 0, "x"));
}

TEST(McapWriter, MisuseIsAnErrorNotACrash) {
  Writer w;
  EXPECT_FALSE(w.open(temp_file("no/such/dir/x.mcap")));
  EXPECT_NE(w.error().find("cannot create"), std::string::npos);
  Writer v;
  ASSERT_TRUE(v.open(temp_file("misuse.mcap")));
  EXPECT_FALSE(v.write(7, 0, "x"));  // no such channel
  EXPECT_NE(v.error().find("unknown channel 7"), std::string::npos);
  EXPECT_FALSE(v.close());  // the file is whole, but a message was refused: not ok
}

TEST(McapWriter, AWriterDestroyedOpenStillEndsTheFile) {
  const fs::path path = temp_file("dropped.mcap");
  {
    Writer w;
    ASSERT_TRUE(w.open(path));
    w.write(w.add_channel(0, "/x", "json"), 5, "{}");
  }
  EXPECT_TRUE(check_file(path).complete);
}

TEST(McapFileCheck, EveryPrefixOfAFileIsIncompleteAndACorruptSummaryIsFound) {
  const fs::path path = temp_file("whole.mcap");
  {
    Writer w;
    ASSERT_TRUE(w.open(path));
    const std::uint16_t c = w.add_channel(w.add_schema("s", "jsonschema", "{}"), "/x", "json");
    for (int i = 0; i < 20; ++i) w.write(c, static_cast<std::uint64_t>(i) * 100, "{\"i\":1}");
    ASSERT_TRUE(w.close());
  }
  const std::string f = slurp(path);
  const fs::path cut = temp_file("cut.mcap");
  // Every prefix near the end (where the summary and footer are), every 13th before.
  for (std::size_t n = 0; n < f.size(); n += n + 200 < f.size() ? 13 : 1) {
    std::ofstream(cut, std::ios::binary | std::ios::trunc)
        .write(f.data(), static_cast<std::streamsize>(n));
    const FileCheck c = check_file(cut);
    ASSERT_FALSE(c.complete) << "a prefix of " << n << " bytes passed";
    EXPECT_FALSE(c.problem.empty());
  }
  std::ofstream(cut, std::ios::binary | std::ios::trunc)
      .write(f.data(), static_cast<std::streamsize>(f.size() - 8));
  EXPECT_NE(check_file(cut).problem.find("no footer"), std::string::npos);
  // A byte of the summary flipped: the footer's CRC says so.
  std::string bad = f;
  bad[bad.size() - 8 - kFooterRecordBytes - 3] ^= 0x01;
  std::ofstream(cut, std::ios::binary | std::ios::trunc)
      .write(bad.data(), static_cast<std::streamsize>(bad.size()));
  EXPECT_NE(check_file(cut).problem.find("CRC"), std::string::npos) << check_file(cut).problem;
  EXPECT_FALSE(check_file(temp_file("absent.mcap")).complete);
}

}  // namespace
}  // namespace qswarm::mcap
