// A blocking TCP client on loopback for the servers' tests (Modbus, HTTP, the acceptor): raw
// bytes out, raw bytes in, and whether the server closed. Each protocol's test adds its framing.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

#include "loopback.h"

namespace drivegate::test {

class TcpClient {
 public:
  // To 127.0.0.1:`port`, from `from` when given (127.0.0.2 is another client address).
  explicit TcpClient(std::uint16_t port, const char* from = nullptr)
      : fd_(::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0)) {
    int one = 1;
    ::setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    if (from != nullptr) {
      sockaddr_in s{};
      s.sin_family = AF_INET;
      ::inet_pton(AF_INET, from, &s.sin_addr);
      if (::bind(fd_, reinterpret_cast<sockaddr*>(&s), sizeof s) != 0) return;
    }
    const sockaddr_in a = loopback(port);
    connected_ = ::connect(fd_, reinterpret_cast<const sockaddr*>(&a), sizeof a) == 0;
  }
  ~TcpClient() {
    if (fd_ >= 0) ::close(fd_);
  }
  TcpClient(const TcpClient&) = delete;
  TcpClient& operator=(const TcpClient&) = delete;

  [[nodiscard]] bool connected() const { return connected_; }
  [[nodiscard]] int fd() const { return fd_; }
  void close() {
    ::close(fd_);
    fd_ = -1;
  }
  void shutdown_write() { ::shutdown(fd_, SHUT_WR); }
  // Closes with a reset (SO_LINGER 0): the server's next read fails, as when a client crashes
  // or its network goes away.
  void abort() {
    const linger l{1, 0};
    ::setsockopt(fd_, SOL_SOCKET, SO_LINGER, &l, sizeof l);
    close();
  }
  // All of it, or false.
  bool send_bytes(const void* data, std::size_t size) {
    const auto* p = static_cast<const char*>(data);
    std::size_t at = 0;
    while (at < size) {
      const ssize_t n = ::send(fd_, p + at, size - at, MSG_NOSIGNAL);
      if (n <= 0) return false;
      at += static_cast<std::size_t>(n);
    }
    return true;
  }
  // What the server has not read yet of what this client sent: the receive queue of the
  // server's end of this connection, as the kernel shows it (/proc/net/tcp, tcp6). nullopt once
  // that end is gone. A test that needs the server to have read one part before the next is
  // sent waits for 0 (ServerThread::eventually: it looks after each of the server's handlers).
  [[nodiscard]] std::optional<std::size_t> unread_by_server() const {
    sockaddr_in self{}, peer{};
    socklen_t n = sizeof self;
    if (::getsockname(fd_, reinterpret_cast<sockaddr*>(&self), &n) != 0) return std::nullopt;
    n = sizeof peer;
    if (::getpeername(fd_, reinterpret_cast<sockaddr*>(&peer), &n) != 0) return std::nullopt;
    // The server's end: local port the server's, remote port ours (columns "local_address
    // rem_address st tx_queue:rx_queue", addresses as hex address:port).
    const unsigned server_port = ntohs(peer.sin_port), client_port = ntohs(self.sin_port);
    for (const char* table : {"/proc/net/tcp", "/proc/net/tcp6"}) {
      std::ifstream in(table);
      std::string line;
      std::getline(in, line);  // the header
      while (std::getline(in, line)) {
        std::istringstream fields(line);
        std::string slot, local, remote, state, queues;
        fields >> slot >> local >> remote >> state >> queues;
        const auto port = [](const std::string& a) {
          return std::stoul(a.substr(a.find(':') + 1), nullptr, 16);
        };
        if (port(local) != server_port || port(remote) != client_port) continue;
        return std::stoul(queues.substr(queues.find(':') + 1), nullptr, 16);
      }
    }
    return std::nullopt;
  }
  bool readable(std::chrono::milliseconds timeout) {
    pollfd p{fd_, POLLIN, 0};
    return ::poll(&p, 1, static_cast<int>(timeout.count())) > 0;
  }
  // True when the server closed the connection within `timeout` (EOF or reset, no data).
  bool closed_by_peer(std::chrono::milliseconds timeout = std::chrono::milliseconds(2000)) {
    if (!readable(timeout)) return false;
    std::uint8_t b;
    return ::recv(fd_, &b, 1, 0) <= 0;
  }

 private:
  int fd_ = -1;
  bool connected_ = false;
};

}  // namespace drivegate::test
