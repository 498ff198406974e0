#include "app/journal_socket.h"

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>

namespace drivegate {

std::string journal_datagram(std::span<const std::string> fields) {
  std::string out;
  for (const std::string& f : fields) {
    const auto eq = f.find('=');
    if (eq == std::string::npos || eq == 0) continue;
    if (f.find('\n', eq) == std::string::npos) {
      out += f;
      out += '\n';
      continue;
    }
    out.append(f, 0, eq);
    out += '\n';
    std::uint64_t n = f.size() - eq - 1;
    for (int i = 0; i < 8; ++i, n >>= 8) out += static_cast<char>(n & 0xFF);
    out.append(f, eq + 1);
    out += '\n';
  }
  return out;
}

JournalSocket::JournalSocket(std::string path) : path_(std::move(path)) {
  if (path_.empty()) {
    const char* env = std::getenv("DRIVEGATE_JOURNAL_SOCKET");
    path_ = env != nullptr && *env != '\0' ? env : kJournalSocket;
  }
  fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ >= 0) {
    // journald's own clients ask for 8 MiB (the kernel caps it at net.core.wmem_max): an entry
    // larger than the send buffer cannot go as one datagram.
    const int size = 8 * 1024 * 1024;
    ::setsockopt(fd_, SOL_SOCKET, SO_SNDBUF, &size, sizeof size);
  }
}

JournalSocket::~JournalSocket() {
  if (fd_ >= 0) ::close(fd_);
}

std::error_code JournalSocket::send(std::span<const std::string> fields) const {
  if (fd_ < 0) return {EBADF, std::generic_category()};
  sockaddr_un to{};
  to.sun_family = AF_UNIX;
  if (path_.size() >= sizeof to.sun_path) return {ENAMETOOLONG, std::generic_category()};
  std::memcpy(to.sun_path, path_.data(), path_.size());
  const std::string d = journal_datagram(fields);
  const ssize_t n = ::sendto(fd_, d.data(), d.size(), MSG_NOSIGNAL | MSG_DONTWAIT,
                             reinterpret_cast<const sockaddr*>(&to), sizeof to);
  if (n < 0) return {errno, std::generic_category()};
  if (static_cast<std::size_t>(n) != d.size()) return {EMSGSIZE, std::generic_category()};
  return {};
}

}  // namespace drivegate
