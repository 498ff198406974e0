// journald's native socket as a test stands it up: a datagram socket bound at a path of the
// test's own, which DRIVEGATE_JOURNAL_SOCKET names to the programs under test
// (app/journal_socket.h). Each datagram is one entry, its fields one a line.
#pragma once

#include <stdlib.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstring>
#include <string>

namespace drivegate::test {

class FakeJournald {
 public:
  explicit FakeJournald(const std::string& path)
      : fd_(::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0)) {
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    std::strncpy(a.sun_path, path.c_str(), sizeof a.sun_path - 1);
    bound_ = ::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  }
  ~FakeJournald() { ::close(fd_); }
  FakeJournald(const FakeJournald&) = delete;
  FakeJournald& operator=(const FakeJournald&) = delete;
  [[nodiscard]] bool bound() const { return bound_; }
  // The next entry, "" if none is waiting.
  std::string receive() {
    char buf[65536];
    const ssize_t n = ::recv(fd_, buf, sizeof buf, MSG_DONTWAIT);
    return n > 0 ? std::string(buf, static_cast<std::size_t>(n)) : std::string();
  }

 private:
  int fd_;
  bool bound_ = false;
};

// DRIVEGATE_JOURNAL_SOCKET set to `path` while it lives, for this process and the programs it
// starts.
class JournalAt {
 public:
  explicit JournalAt(const std::string& path) {
    ::setenv("DRIVEGATE_JOURNAL_SOCKET", path.c_str(), 1);
  }
  ~JournalAt() { ::unsetenv("DRIVEGATE_JOURNAL_SOCKET"); }
  JournalAt(const JournalAt&) = delete;
  JournalAt& operator=(const JournalAt&) = delete;
};

}  // namespace drivegate::test
