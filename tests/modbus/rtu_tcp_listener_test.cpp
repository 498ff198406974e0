// RtuTcpListener (daemon/modbus/rtu_tcp_listener.h) over loopback, on a manual clock, with a
// backend whose writes complete when the test says: what a client that half-closes its side
// (shutdown SHUT_WR) after a request gets back, as the Modbus TCP listener's clients do
// (modbus/connection.h): every request it sent carried out and answered, then the close.
#include "modbus/rtu_tcp_listener.h"

#include <arpa/inet.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <spdlog/sinks/null_sink.h>
#include <sys/socket.h>
#include <unistd.h>

#include <boost/asio/io_context.hpp>
#include <functional>

#include "hand_backend.h"
#include "loopback.h"
#include "manual_clock.h"
#include "modbus_serial/serial_codec.h"

namespace drivegate::slave::rtu_tcp_listener_test {
namespace {

using namespace std::chrono_literals;
using modbus::Exception;
using modbus_serial::Framing;

const Bytes kWrite = {0x06, 0x00, 0x00, 0x00, 0x01};          // FC 06, holding 0 = 1 (a run)
const Bytes kRead = {0x03, 0x00, 0x10, 0x00, 0x02};           // FC 03, holding 16, 2 registers
const Bytes kReadReply = {0x03, 0x04, 0x00, 116, 0x00, 117};  // 100 + address

class RtuTcpListenerTest : public ::testing::Test {
 protected:
  RtuTcpListenerTest() {
    RtuTcpOptions o;
    o.host = "127.0.0.1";
    o.port = 0;
    auto policy = std::make_shared<SlavePolicy>();
    policy->session.access = AccessLevel::operate;
    policy->session.source.kind = SourceKind::modbus_serial;
    listener_ = std::make_shared<RtuTcpListener>(io_, clock_, backend_, o, policy, log_);
    EXPECT_FALSE(listener_->listen());
  }
  ~RtuTcpListenerTest() override {
    if (fd_ >= 0) ::close(fd_);
    listener_->close();
    pump([] { return false; }, 20ms);
  }
  // A client connected to the listener, and the listener's side of it accepted.
  void connect() {
    fd_ = test::connect_loopback(listener_->port());
    ASSERT_GE(fd_, 0);
    ASSERT_TRUE(pump([&] { return listener_->clients() == 1; }));
  }
  void send(std::uint8_t unit, const Bytes& pdu) {
    const Bytes frame = modbus_serial::encode(Framing::rtu, unit, pdu);
    ASSERT_EQ(::write(fd_, frame.data(), frame.size()), static_cast<ssize_t>(frame.size()));
  }
  // Runs the listener's event loop until `done` or `limit` passed; whether `done`. It looks
  // after each handler, and waits for the next one (a client's bytes, an accept) in between.
  bool pump(const std::function<bool()>& done, std::chrono::milliseconds limit = 2s) {
    const auto until = std::chrono::steady_clock::now() + limit;
    while (!done()) {
      const auto now = std::chrono::steady_clock::now();
      if (now >= until) return false;
      if (io_.stopped()) io_.restart();
      if (io_.run_one_for(until - now) == 0 && io_.stopped()) return done();  // nothing to wait for
    }
    return true;
  }
  // What the client has been sent so far, and whether the listener closed its side after it.
  bool closed_ = false;
  Bytes received() {
    Bytes in;
    for (;;) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 0) <= 0) break;
      std::uint8_t buf[256];
      const ssize_t n = ::read(fd_, buf, sizeof buf);
      if (n <= 0) {
        closed_ = true;
        break;
      }
      in.insert(in.end(), buf, buf + n);
    }
    return in;
  }

  // Before io_: the listener's timers detach from it as the io_context goes.
  test::ManualClock clock_;
  boost::asio::io_context io_;
  HandBackend backend_;
  std::shared_ptr<spdlog::logger> log_ =
      std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::null_sink_mt>());
  std::shared_ptr<RtuTcpListener> listener_;
  int fd_ = -1;
};

// The run is with its drive when the client half-closes: the connection waits for it, sends the
// drive's answer (the echo, CRC and all), and only then closes.
TEST_F(RtuTcpListenerTest, AHalfClosedClientGetsTheReplyToAWriteStillWithItsDevice) {
  ASSERT_NO_FATAL_FAILURE(connect());
  ASSERT_NO_FATAL_FAILURE(send(1, kWrite));
  ::shutdown(fd_, SHUT_WR);
  ASSERT_TRUE(pump([&] { return backend_.pending.size() == 1; }));
  pump([] { return false; }, 50ms);  // the end of its input reaches the listener meanwhile
  Bytes got = received();
  EXPECT_TRUE(got.empty());
  EXPECT_FALSE(closed_) << "closed with the write still at its device";
  EXPECT_EQ(listener_->clients(), 1u);
  backend_.pending[0](Exception::none);
  ASSERT_TRUE(pump([&] {
    const Bytes more = received();
    got.insert(got.end(), more.begin(), more.end());
    return closed_;
  })) << "never closed after the reply";
  EXPECT_EQ(got, modbus_serial::encode(Framing::rtu, 1, kWrite));
  EXPECT_EQ(listener_->clients(), 0u);
}

// Requests sent together before the half-close are all answered, in order, the read at once and
// the write once its drive took it; a failed write gets its exception.
TEST_F(RtuTcpListenerTest, AHalfClosedClientGetsEveryAnswerItAskedFor) {
  ASSERT_NO_FATAL_FAILURE(connect());
  ASSERT_NO_FATAL_FAILURE(send(1, kRead));
  ASSERT_TRUE(pump([&] { return !received().empty(); }));
  ASSERT_NO_FATAL_FAILURE(send(2, kWrite));
  ::shutdown(fd_, SHUT_WR);
  ASSERT_TRUE(pump([&] { return backend_.pending.size() == 1; }));
  backend_.pending[0](Exception::gateway_target_failed);
  Bytes got;
  ASSERT_TRUE(pump([&] {
    const Bytes more = received();
    got.insert(got.end(), more.begin(), more.end());
    return closed_;
  }));
  EXPECT_EQ(got, modbus_serial::encode(Framing::rtu, 2, Bytes{0x86, 0x0B}));
}

// Half a frame, then the half-close: nothing is pending, the rest will never come; closed.
TEST_F(RtuTcpListenerTest, AHalfClosedClientWithHalfAFrameIsClosed) {
  ASSERT_NO_FATAL_FAILURE(connect());
  const Bytes frame = modbus_serial::encode(Framing::rtu, 1, kWrite);
  ASSERT_EQ(::write(fd_, frame.data(), 4), 4);
  ::shutdown(fd_, SHUT_WR);
  ASSERT_TRUE(pump([&] {
    received();
    return closed_;
  }));
  EXPECT_TRUE(backend_.writes.empty());
  EXPECT_EQ(listener_->clients(), 0u);
}

}  // namespace
}  // namespace drivegate::slave::rtu_tcp_listener_test
