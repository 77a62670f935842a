#include "common/transport/regular_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace qswarm {

RegularFile open_regular_file(const std::filesystem::path& path, std::uintmax_t max_bytes) {
  RegularFile f;
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) {
    f.problem =
        errno == ENOENT ? RegularFile::Problem::kMissing : RegularFile::Problem::kUnreadable;
    f.why =
        errno == ENOENT ? "missing" : std::string("cannot be read (") + std::strerror(errno) + ")";
    return f;
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    f.problem = RegularFile::Problem::kNotRegular;
    f.why = "not a regular file";
    return f;
  }
  if (static_cast<std::uintmax_t>(st.st_size) > max_bytes) {
    ::close(fd);
    f.problem = RegularFile::Problem::kTooLarge;
    f.why = "larger than " + std::to_string(max_bytes) + " bytes";
    return f;
  }
  const int flags = ::fcntl(fd, F_GETFL);
  if (flags >= 0) ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
  f.fd = fd;
  f.size = static_cast<std::uintmax_t>(st.st_size);
  return f;
}

std::string read_regular_file(const std::filesystem::path& path, std::uintmax_t max_bytes,
                              RegularFile& f) {
  f = open_regular_file(path, max_bytes);
  if (f.problem != RegularFile::Problem::kNone) return {};
  std::string text;
  char buf[65536];
  for (;;) {
    const ssize_t n = ::read(f.fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      f.problem = RegularFile::Problem::kUnreadable;
      f.why = std::string("cannot be read (") + std::strerror(errno) + ")";
      text.clear();
      break;
    }
    if (n == 0) break;
    text.append(buf, static_cast<std::size_t>(n));
    if (text.size() > max_bytes) {  // it grew since it was opened
      f.problem = RegularFile::Problem::kTooLarge;
      f.why = "larger than " + std::to_string(max_bytes) + " bytes";
      text.clear();
      break;
    }
  }
  ::close(f.fd);
  f.fd = -1;
  return text;
}

}  // namespace qswarm
