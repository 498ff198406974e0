// A Modbus server on an ephemeral loopback port, run by its own io_context thread, with a fake
// backend; raw socket clients for the byte-exact tests.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <spdlog/sinks/null_sink.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>
#include <unistd.h>

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <chrono>
#include <future>
#include <memory>
#include <thread>
#include <vector>

#include "fake_backend.h"
#include "server.h"

namespace drivegate::modbus::test {

using Bytes = std::vector<std::uint8_t>;
using namespace std::chrono_literals;

class Harness {
 public:
  explicit Harness(ServerOptions options = {}) {
    for (auto& l : options.listeners) {
      l.host = l.host == "*" ? "127.0.0.1" : l.host;
      l.port = 0;
    }
    auto log = std::make_shared<spdlog::logger>("modbus-test",
                                                std::make_shared<spdlog::sinks::null_sink_st>());
    server_ = std::make_unique<Server>(io_, backend_, options, log);
    error_ = server_->listen();
    thread_ = std::thread([this] { io_.run(); });
  }
  ~Harness() {
    on_io([this] { server_->close(); });
    guard_.reset();
    thread_.join();
  }

  std::error_code listen_error() const { return error_; }
  std::uint16_t port(std::size_t listener = 0) const { return server_->port(listener); }

  // Runs `f` on the server's thread and returns its result.
  template <class F>
  auto on_io(F f) -> decltype(f()) {
    std::packaged_task<decltype(f())()> task(std::move(f));
    auto result = task.get_future();
    boost::asio::post(io_, [&task] { task(); });
    return result.get();
  }
  Server& server() { return *server_; }
  ServerStats stats() {
    return on_io([this] { return server_->stats(); });
  }
  std::size_t clients() {
    return on_io([this] { return server_->client_count(); });
  }
  // Waits (up to 5 s) until the server counts `n` clients.
  bool wait_clients(std::size_t n) {
    for (int i = 0; i < 500; ++i) {
      if (clients() == n) return true;
      std::this_thread::sleep_for(10ms);
    }
    return false;
  }
  // Backend access, on the server's thread.
  template <class F>
  auto with_backend(F f) {
    return on_io([this, &f] { return f(backend_); });
  }

 private:
  boost::asio::io_context io_;
  FakeBackend backend_;
  std::unique_ptr<Server> server_;
  boost::asio::executor_work_guard<boost::asio::io_context::executor_type> guard_{
      io_.get_executor()};
  std::thread thread_;
  std::error_code error_;
};

// A blocking TCP client speaking raw bytes.
class RawClient {
 public:
  explicit RawClient(std::uint16_t port) {
    fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    int one = 1;
    ::setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    connected_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  }
  ~RawClient() {
    if (fd_ >= 0) ::close(fd_);
  }
  RawClient(const RawClient&) = delete;
  RawClient& operator=(const RawClient&) = delete;

  bool connected() const { return connected_; }
  void close() {
    ::close(fd_);
    fd_ = -1;
  }
  void shutdown_write() { ::shutdown(fd_, SHUT_WR); }
  // Closes with a reset (SO_LINGER 0): the server's next read fails, as when a client crashes
  // or its network goes away.
  void reset() {
    const linger l{1, 0};
    ::setsockopt(fd_, SOL_SOCKET, SO_LINGER, &l, sizeof l);
    close();
  }
  bool send(const Bytes& b) {
    return ::send(fd_, b.data(), b.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(b.size());
  }
  // Exactly `n` bytes, or fewer if the peer closed or `timeout` passed.
  Bytes recv(std::size_t n, std::chrono::milliseconds timeout = 2000ms) {
    Bytes out;
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (out.size() < n) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          end - std::chrono::steady_clock::now());
      if (left.count() <= 0 || !readable(left)) break;
      std::uint8_t buf[512];
      const auto got = ::recv(fd_, buf, std::min(sizeof buf, n - out.size()), 0);
      if (got <= 0) break;
      out.insert(out.end(), buf, buf + got);
    }
    return out;
  }
  // One whole MBAP response (header, then as many bytes as its length says).
  Bytes reply(std::chrono::milliseconds timeout = 2000ms) {
    Bytes h = recv(7, timeout);
    if (h.size() < 7) return h;
    const std::size_t length = (h[4] << 8) | h[5];
    const Bytes rest = recv(length - 1, timeout);
    h.insert(h.end(), rest.begin(), rest.end());
    return h;
  }
  // True when the server closed the connection within `timeout` (EOF or reset, no data).
  bool closed_by_peer(std::chrono::milliseconds timeout = 2000ms) {
    if (!readable(timeout)) return false;
    std::uint8_t b;
    return ::recv(fd_, &b, 1, 0) <= 0;
  }
  bool readable(std::chrono::milliseconds timeout) {
    pollfd p{fd_, POLLIN, 0};
    return ::poll(&p, 1, static_cast<int>(timeout.count())) > 0;
  }

 private:
  int fd_ = -1;
  bool connected_ = false;
};

// An MBAP request: transaction id, unit, PDU.
inline Bytes request(std::uint16_t transaction, std::uint8_t unit, const Bytes& pdu) {
  const auto length = static_cast<std::uint16_t>(pdu.size() + 1);
  Bytes b{static_cast<std::uint8_t>(transaction >> 8),
          static_cast<std::uint8_t>(transaction),
          0x00,
          0x00,
          static_cast<std::uint8_t>(length >> 8),
          static_cast<std::uint8_t>(length),
          unit};
  b.insert(b.end(), pdu.begin(), pdu.end());
  return b;
}
inline Bytes operator+(Bytes a, const Bytes& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

}  // namespace drivegate::modbus::test
