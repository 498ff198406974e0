// The journal's native protocol, sent by hand: one datagram per entry on journald's AF_UNIX
// socket, each field "NAME=value\n", or, for a value with a newline in it, "NAME\n", the value's
// length as 64-bit little endian, the value and "\n" (systemd's "Native Journal Protocol",
// https://systemd.io/JOURNAL_NATIVE_PROTOCOL/). Not sd_journal_sendv(3): that reports success
// when the socket is not there (ENOENT: "fail silently if the journal is not available"), and an
// audit record must reach the journal or stderr, never neither (app/logging.h).
#pragma once

#include <span>
#include <string>
#include <system_error>

namespace drivegate {

// journald's socket (systemd-journald.service(8)): also where a LogNamespace='s service finds its
// namespace's.
inline constexpr const char* kJournalSocket = "/run/systemd/journal/socket";

// One entry's datagram; `fields` are "NAME=value" each (one without '=' is left out).
std::string journal_datagram(std::span<const std::string> fields);

class JournalSocket {
 public:
  // `path`: journald's socket; empty: DRIVEGATE_JOURNAL_SOCKET from the environment if set (tests
  // run without journald), else kJournalSocket.
  explicit JournalSocket(std::string path = {});
  ~JournalSocket();
  JournalSocket(const JournalSocket&) = delete;
  JournalSocket& operator=(const JournalSocket&) = delete;

  // Sends one entry without waiting: an error if the journal did not take it (no socket, nobody
  // listening, its queue full, the entry too large for one datagram).
  std::error_code send(std::span<const std::string> fields) const;
  [[nodiscard]] const std::string& path() const { return path_; }

 private:
  std::string path_;
  int fd_ = -1;
};

}  // namespace drivegate
