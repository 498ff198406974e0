#include "base/read_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace drivegate {

namespace {

const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

std::string size_text(std::size_t bytes) {
  if (bytes >= 1024 * 1024 && bytes % (1024 * 1024) == 0) {
    return std::to_string(bytes / (1024 * 1024)) + " MiB";
  }
  if (bytes >= 1024 && bytes % 1024 == 0) return std::to_string(bytes / 1024) + " KiB";
  return std::to_string(bytes) + " bytes";
}

// Opens without blocking (O_NONBLOCK: a FIFO without a writer opens at once) and checks the
// open file itself (fstat: no race with a rename in between). -1 and `error` when refused.
int open_regular(const std::filesystem::path& path, struct stat& st, std::string& error) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) {
    error = path.string() + ": cannot open: " + std::strerror(errno);
    return -1;
  }
  if (::fstat(fd, &st) != 0) {
    error = path.string() + ": " + std::strerror(errno);
    ::close(fd);
    return -1;
  }
  if (!S_ISREG(st.st_mode)) {
    error = path.string() + ": " + kind_of(st.st_mode) + ", not a regular file";
    ::close(fd);
    return -1;
  }
  return fd;
}

}  // namespace

std::optional<std::string> read_regular_file(const std::filesystem::path& path,
                                             std::size_t max_bytes, std::string& error) {
  struct stat st {};
  const int fd = open_regular(path, st, error);
  if (fd < 0) return std::nullopt;
  if (static_cast<std::size_t>(st.st_size) > max_bytes) {
    error = path.string() + ": " + std::to_string(st.st_size) + " bytes, more than the " +
            size_text(max_bytes) + " allowed";
    ::close(fd);
    return std::nullopt;
  }
  std::string out;
  out.resize(static_cast<std::size_t>(st.st_size));
  std::size_t got = 0;
  while (got < out.size()) {
    const ssize_t n = ::read(fd, out.data() + got, out.size() - got);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    got += static_cast<std::size_t>(n);
  }
  ::close(fd);
  out.resize(got);  // a file that shrank meanwhile: what it held
  return out;
}

bool is_readable_regular_file(const std::filesystem::path& path, std::string& error) {
  struct stat st {};
  const int fd = open_regular(path, st, error);
  if (fd < 0) return false;
  ::close(fd);
  return true;
}

}  // namespace drivegate
