#include "common/mcap/file_check.hpp"

#include <fstream>
#include <system_error>

#include "common/mcap/records.hpp"

namespace qswarm::mcap {
namespace {

std::string read_at(std::ifstream& in, std::uint64_t at, std::uint64_t n) {
  std::string s(n, '\0');
  in.seekg(static_cast<std::streamoff>(at));
  in.read(s.data(), static_cast<std::streamsize>(n));
  if (static_cast<std::uint64_t>(in.gcount()) != n) s.clear();
  return s;
}

}  // namespace

FileCheck check_file(const std::filesystem::path& path) {
  FileCheck c;
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) {
    c.problem = "cannot read (" + ec.message() + ")";
    return c;
  }
  c.bytes = size;
  std::ifstream in(path, std::ios::binary);
  const std::string_view magic(kMagic.data(), kMagic.size());
  if (!in || size < magic.size() || read_at(in, 0, magic.size()) != magic) {
    c.problem = "not an MCAP file (no magic at its start)";
    return c;
  }
  if (size < 2 * magic.size() + kFooterRecordBytes ||
      read_at(in, size - magic.size(), magic.size()) != magic) {
    c.problem = "no footer: the file was cut short (its writer stopped before the end)";
    return c;
  }
  const std::uint64_t footer_at = size - magic.size() - kFooterRecordBytes;
  const std::string footer = read_at(in, footer_at, kFooterRecordBytes);
  if (footer.size() != kFooterRecordBytes || footer[0] != static_cast<char>(Op::kFooter) ||
      read_le(footer, 1, 8) != kFooterRecordBytes - 9) {
    c.problem = "no footer record before the trailing magic";
    return c;
  }
  const std::uint64_t summary_start = read_le(footer, 9, 8);
  const std::uint64_t offsets_start = read_le(footer, 17, 8);
  const auto crc = static_cast<std::uint32_t>(read_le(footer, 25, 4));
  const std::uint64_t crc_from = summary_start   ? summary_start
                                 : offsets_start ? offsets_start
                                                 : footer_at;
  if (crc_from > footer_at) {
    c.problem = "the footer points past itself";
    return c;
  }
  if (crc != 0) {
    const std::string covered = read_at(in, crc_from, footer_at - crc_from + 25);
    if (covered.empty() || crc32(covered) != crc) {
      c.problem = "the summary's CRC does not match";
      return c;
    }
  }
  c.complete = true;
  return c;
}

}  // namespace qswarm::mcap
