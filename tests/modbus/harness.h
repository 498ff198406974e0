// A Modbus server on an ephemeral loopback port, run by its own io_context thread, with a fake
// backend; raw socket clients for the byte-exact tests.
#pragma once

#include <sys/socket.h>

#include <chrono>
#include <memory>
#include <thread>
#include <vector>

#include "fake_backend.h"
#include "server.h"
#include "server_thread.h"
#include "tcp_client.h"

namespace drivegate::modbus::test {

using Bytes = std::vector<std::uint8_t>;
using namespace std::chrono_literals;

// Listeners on loopback, ephemeral ports.
inline ServerOptions on_loopback(ServerOptions options) {
  for (auto& l : options.listeners) {
    l.host = l.host == "*" ? "127.0.0.1" : l.host;
    l.port = 0;
  }
  return options;
}

class Harness : public drivegate::test::ServerThread<Server, FakeBackend> {
 public:
  explicit Harness(ServerOptions options = {})
      : ServerThread(on_loopback(std::move(options)), "modbus-test") {}

  std::uint16_t port(std::size_t listener = 0) { return server().port(listener); }
  // Waits until the server has read `bytes` in all from its clients.
  bool received(std::uint64_t bytes) {
    return eventually([this, bytes] { return server().stats().bytes_received >= bytes; });
  }
  using ServerThread::source;  // the backend: only on the server's thread (on_io, eventually)
  // Backend access, on the server's thread.
  template <class F>
  auto with_backend(F f) {
    return on_io([this, &f] { return f(source()); });
  }
};

// A blocking TCP client speaking raw bytes.
class RawClient : public drivegate::test::TcpClient {
 public:
  explicit RawClient(std::uint16_t port) : TcpClient(port) {}
  void reset() { abort(); }
  bool send(const Bytes& b) { return send_bytes(b.data(), b.size()); }
  // Exactly `n` bytes, or fewer if the peer closed or `timeout` passed.
  Bytes recv(std::size_t n, std::chrono::milliseconds timeout = 2000ms) {
    Bytes out;
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (out.size() < n) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          end - std::chrono::steady_clock::now());
      if (left.count() <= 0 || !readable(left)) break;
      std::uint8_t buf[512];
      const auto got = ::recv(fd(), buf, std::min(sizeof buf, n - out.size()), 0);
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
