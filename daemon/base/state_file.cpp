#include "base/state_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>  // renameat, renameat2 and RENAME_NOREPLACE (glibc: _GNU_SOURCE)
#include <cstring>
#include <string>

namespace drivegate {
namespace {

std::error_code last_error() {
  return {errno, std::generic_category()};
}

// Closes a descriptor once, whatever path the function leaves by.
class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  [[nodiscard]] int get() const { return fd_; }
  std::error_code close() {
    const int fd = fd_;
    fd_ = -1;
    return ::close(fd) == 0 ? std::error_code{} : last_error();
  }

 private:
  int fd_;
};

// Clears the temporary's name: whatever has it is never opened. A directory there is set aside
// (rmdir would take an empty one only, and it may hold someone's files).
std::error_code clear_name(int dir_fd, const std::string& name) {
  if (::unlinkat(dir_fd, name.c_str(), 0) == 0 || errno == ENOENT) return {};
  if (errno != EISDIR && errno != EPERM) return last_error();
  std::string ignored;
  if (set_aside(dir_fd, name, ignored)) return {};
  return std::make_error_code(std::errc::is_a_directory);
}

// A new file (O_EXCL: never one that was there, nor through a link) with `content`, synced.
std::error_code write_synced(int dir_fd, const std::string& name, std::string_view content) {
  if (auto ec = clear_name(dir_fd, name)) return ec;
  Fd fd(::openat(dir_fd, name.c_str(),
                 O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC, 0600));
  if (fd.get() < 0) return last_error();
  if (auto ec = write_all(fd.get(), content)) return ec;
  if (::fsync(fd.get()) != 0) return last_error();
  return fd.close();
}

}  // namespace

std::error_code write_all(int fd, std::string_view bytes) {
  while (!bytes.empty()) {
    const ssize_t n = ::write(fd, bytes.data(), bytes.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      return last_error();
    }
    bytes.remove_prefix(static_cast<std::size_t>(n));
  }
  return {};
}

std::error_code replace_file_at(int dir_fd, const std::string& name, std::string_view content) {
  const std::string tmp = name + ".tmp";
  if (auto ec = write_synced(dir_fd, tmp, content)) {
    ::unlinkat(dir_fd, tmp.c_str(), 0);
    return ec;
  }
  if (::renameat(dir_fd, tmp.c_str(), dir_fd, name.c_str()) != 0) {
    const auto ec = last_error();
    ::unlinkat(dir_fd, tmp.c_str(), 0);
    return ec;
  }
  // The rename itself is durable once the directory is.
  if (::fsync(dir_fd) != 0) return last_error();
  return {};
}

std::error_code replace_file(const std::filesystem::path& file, std::string_view content) {
  // The directory is the one the configuration names (a link to it is the administrator's).
  const auto dir = file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
  Fd d(::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (d.get() < 0) return last_error();
  if (auto ec = replace_file_at(d.get(), file.filename().string(), content)) return ec;
  return d.close();
}

std::optional<std::string> set_aside(int dir_fd, const std::string& name, std::string& error) {
  for (int n = 1; n <= 9; ++n) {
    const std::string to = name + (n == 1 ? ".bad" : ".bad-" + std::to_string(n));
    // RENAME_NOREPLACE: an earlier file set aside is kept, the next name tried.
    if (::renameat2(dir_fd, name.c_str(), dir_fd, to.c_str(), RENAME_NOREPLACE) == 0) return to;
    if (errno != EEXIST) {
      error = name + ": cannot set it aside: " + std::strerror(errno);
      return std::nullopt;
    }
  }
  error = name + ": cannot set it aside: " + name + ".bad to .bad-9 are all taken";
  return std::nullopt;
}

}  // namespace drivegate
