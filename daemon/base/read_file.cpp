#include "base/read_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace drivegate {

namespace {

std::string size_text(std::size_t bytes) {
  if (bytes >= 1024 * 1024 && bytes % (1024 * 1024) == 0) {
    return std::to_string(bytes / (1024 * 1024)) + " MiB";
  }
  if (bytes >= 1024 && bytes % 1024 == 0) return std::to_string(bytes / 1024) + " KiB";
  return std::to_string(bytes) + " bytes";
}

}  // namespace

const char* file_kind(mode_t mode) {
  if (S_ISREG(mode)) return "a regular file";
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISLNK(mode)) return "a symbolic link";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

// Opens without blocking (O_NONBLOCK: a FIFO without a writer opens at once) and checks the open
// file itself (fstat: no race with a rename in between).
int open_regular_file(int dir_fd, const std::string& name, int flags, Links links,
                      std::string& error) {
  const int extra = links == Links::refuse ? O_NOFOLLOW : 0;
  const int fd = ::openat(dir_fd, name.c_str(), flags | extra | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) {
    const int e = errno;
    error = e == ELOOP && links == Links::refuse ? name + ": a symbolic link, not followed"
                                                 : name + ": cannot open: " + std::strerror(e);
    errno = e;
    return -1;
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const int e = errno;
    error = name + ": " + std::strerror(e);
    ::close(fd);
    errno = e;
    return -1;
  }
  if (!S_ISREG(st.st_mode)) {
    error = name + ": " + file_kind(st.st_mode) + ", not a regular file";
    ::close(fd);
    errno = EINVAL;
    return -1;
  }
  return fd;
}

std::optional<std::string> read_regular_file(const std::filesystem::path& path,
                                             std::size_t max_bytes, std::string& error,
                                             Links links) {
  const int fd = open_regular_file(AT_FDCWD, path.string(), O_RDONLY, links, error);
  if (fd < 0) return std::nullopt;
  struct stat st {};
  ::fstat(fd, &st);
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
  const int fd = open_regular_file(AT_FDCWD, path.string(), O_RDONLY, Links::follow, error);
  if (fd < 0) return false;
  ::close(fd);
  return true;
}

}  // namespace drivegate
