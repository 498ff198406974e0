#include "base/state_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
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

std::error_code write_synced(const std::filesystem::path& file, std::string_view content) {
  Fd fd(::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NOFOLLOW, 0600));
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

std::error_code replace_file(const std::filesystem::path& file, std::string_view content) {
  const std::filesystem::path tmp = file.string() + ".tmp";
  if (auto ec = write_synced(tmp, content)) {
    ::unlink(tmp.c_str());
    return ec;
  }
  if (::rename(tmp.c_str(), file.c_str()) != 0) {
    const auto ec = last_error();
    ::unlink(tmp.c_str());
    return ec;
  }
  // The rename itself is durable once the directory is.
  const auto dir = file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
  Fd d(::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (d.get() < 0) return last_error();
  if (::fsync(d.get()) != 0) return last_error();
  return d.close();
}

}  // namespace drivegate
