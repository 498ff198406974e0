// The acceptor: client cap, descriptor hygiene, shutdown, addresses.
#include <dirent.h>
#include <gtest/gtest.h>
#include <modbus.h>

#include <optional>
#include <string>

#include "harness.h"

namespace drivegate::modbus {
namespace {

using namespace test;

std::size_t open_descriptors() {
  std::size_t n = 0;
  if (DIR* d = ::opendir("/proc/self/fd")) {
    while (::readdir(d) != nullptr) ++n;
    ::closedir(d);
  }
  return n;
}

const Bytes kRead = request(1, 1, {0x03, 0x00, 0x00, 0x00, 0x01});
const Bytes kReadReply{0x00, 0x01, 0x00, 0x00, 0x00, 0x05, 0x01, 0x03, 0x02, 0x00, 0x00};

TEST(Server, ListensOnAnEphemeralPort) {
  Harness h;
  ASSERT_FALSE(h.listen_error());
  EXPECT_NE(h.port(), 0);
}

TEST(Server, RefusesAnAddressThatDoesNotParse) {
  ServerOptions o;
  o.listeners[0].host = "not-an-address";
  Harness h(o);
  EXPECT_EQ(h.listen_error(), std::errc::invalid_argument);
}

TEST(Server, ListensOnIpv6Loopback) {
  ServerOptions o;
  o.listeners[0].host = "[::1]";
  Harness h(o);
  if (h.listen_error()) GTEST_SKIP() << "no IPv6: " << h.listen_error().message();
  modbus_t* ctx = modbus_new_tcp_pi("::1", std::to_string(h.port()).c_str());
  modbus_set_slave(ctx, 1);
  ASSERT_EQ(modbus_connect(ctx), 0);
  std::uint16_t v;
  EXPECT_EQ(modbus_read_registers(ctx, 0, 1, &v), 1);
  modbus_close(ctx);
  modbus_free(ctx);
}

TEST(Server, ClientCapAcceptsAndClosesTheExtraClient) {
  ServerOptions o;
  o.max_clients = 2;
  Harness h(o);
  RawClient a(h.port());
  RawClient b(h.port());
  ASSERT_TRUE(h.wait_clients(2));
  RawClient extra(h.port());
  ASSERT_TRUE(extra.connected());
  EXPECT_TRUE(extra.closed_by_peer(1000ms));
  // The two clients are still served.
  ASSERT_TRUE(a.send(kRead));
  EXPECT_EQ(a.reply(), kReadReply);
  ASSERT_TRUE(b.send(kRead));
  EXPECT_EQ(b.reply(), kReadReply);
  EXPECT_EQ(h.stats().connections_refused, 1u);
  // Once one leaves, a newcomer is served.
  a.close();
  ASSERT_TRUE(h.wait_clients(1));
  RawClient late(h.port());
  ASSERT_TRUE(late.send(kRead));
  EXPECT_EQ(late.reply(), kReadReply);
}

// 10,000 connect / disconnect cycles leak no descriptor.
TEST(Server, TenThousandConnectDisconnectCyclesLeakNoDescriptor) {
  Harness h;
  const std::size_t before = open_descriptors();
  for (int i = 0; i < 10000; ++i) {
    RawClient c(h.port());
    ASSERT_TRUE(c.connected());
    if (i % 10 == 0) {  // some ask first, some leave at once
      ASSERT_TRUE(c.send(kRead));
      ASSERT_EQ(c.reply(), kReadReply);
    }
  }
  // Every connection accepted first: the last ones may still wait in the listen backlog while
  // the count of clients is already 0 (seen under ASan on a loaded machine).
  const auto taken = [&h] {
    const auto s = h.server().stats();
    return s.connections_accepted + s.connections_refused;
  };
  h.eventually([&taken] { return taken() >= 10000; });
  ASSERT_EQ(h.on_io(taken), 10000u);
  ASSERT_TRUE(h.wait_clients(0));
  EXPECT_EQ(open_descriptors(), before);
  EXPECT_EQ(h.stats().connections_active, 0u);
}

TEST(Server, CloseDisconnectsEveryClientAndLeavesNothingRunning) {
  drivegate::test::ManualClock clock;  // outlives io (support/server_thread.h)
  boost::asio::io_context io;
  FakeBackend backend;
  backend.mode = FakeBackend::Mode::deferred;
  auto log = std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::null_sink_st>());
  ServerOptions o;
  o.listeners[0].host = "127.0.0.1";
  o.listeners[0].port = 0;
  auto server = std::make_unique<Server>(io, clock, backend, o, log);
  ASSERT_FALSE(server->listen());
  const auto port = server->port();
  std::thread client([port] {
    RawClient a(port);
    RawClient b(port);
    a.send(request(1, 1, {0x06, 0x00, 0x01, 0x00, 0x01}));  // stays pending
    b.send(kRead);
    b.reply();
    EXPECT_TRUE(a.closed_by_peer(5000ms));
    EXPECT_TRUE(b.closed_by_peer(5000ms));
  });
  // Serve until the write is pending and the read answered, then close.
  while (backend.pending.empty() || server->stats().responses < 1) io.run_one();
  server->close();
  io.restart();
  io.run();  // returns: no accept, no connection, no timer left
  client.join();
  EXPECT_EQ(server->client_count(), 0u);
  backend.complete();  // the late `done` of a closed connection is harmless
  io.restart();
  io.run();
  server.reset();
}

TEST(Server, CountsRequestsAndConnections) {
  Harness h;
  {
    RawClient c(h.port());
    ASSERT_TRUE(c.send(kRead + request(2, 1, {0x07})));
    EXPECT_EQ(c.reply(), kReadReply);
    EXPECT_EQ(c.reply(), (Bytes{0x00, 0x02, 0x00, 0x00, 0x00, 0x03, 0x01, 0x87, 0x01}));
  }
  ASSERT_TRUE(h.wait_clients(0));
  const auto s = h.stats();
  EXPECT_EQ(s.connections_accepted, 1u);
  EXPECT_EQ(s.requests, 2u);
  EXPECT_EQ(s.responses, 2u);
  EXPECT_EQ(s.exceptions[0x01], 1u);
}

// --- limits changed while running (Server::set_limits) -----------------------------------

void set_limits(Harness& h, const ServerLimits& l) {
  h.on_io([&h, &l] { h.server().set_limits(l); });
}

ServerOptions with_idle_timeout(std::chrono::milliseconds idle) {
  ServerOptions o;
  o.idle_timeout = idle;
  return o;
}

// The documented rule: a new idle_timeout applies to open connections at once, measured from
// their last request, without closing the others.
TEST(ServerLimits, ShorterIdleTimeoutAppliesToAnAlreadyOpenConnection) {
  Harness s(with_idle_timeout(60s));
  ASSERT_FALSE(s.listen_error());
  RawClient silent(s.port());
  RawClient recent(s.port());
  RawClient busy(s.port());
  ASSERT_TRUE(silent.send(kRead));
  ASSERT_EQ(silent.reply(), kReadReply);
  s.advance(400ms);
  ASSERT_TRUE(recent.send(kRead));
  ASSERT_EQ(recent.reply(), kReadReply);
  ASSERT_TRUE(busy.send(kRead));
  ASSERT_EQ(busy.reply(), kReadReply);

  set_limits(s, {32, 2000ms, 300ms});
  EXPECT_EQ(s.on_io([&s] { return s.server().limits(); }), (ServerLimits{32, 2000ms, 300ms}));
  // `silent` (400 ms without a request, past the new 300 ms) is closed at once rather than 60 s
  // after its request; `recent` 300 ms after its request, not earlier; `busy`, which keeps
  // asking, is served throughout.
  EXPECT_TRUE(silent.closed_by_peer(2000ms));
  s.advance(250ms);
  ASSERT_TRUE(busy.send(kRead));
  ASSERT_EQ(busy.reply(), kReadReply);
  s.advance(49ms);  // 299 ms after its request
  EXPECT_FALSE(recent.closed_by_peer(100ms));
  s.advance(1ms);
  EXPECT_TRUE(recent.closed_by_peer(2000ms));
  EXPECT_FALSE(busy.closed_by_peer(10ms));
  ASSERT_TRUE(busy.send(kRead));
  EXPECT_EQ(busy.reply(), kReadReply);
  EXPECT_EQ(s.stats().idle_timeouts, 2u);
  EXPECT_TRUE(s.wait_clients(1));
}

TEST(ServerLimits, LongerIdleTimeoutKeepsAnAlreadyOpenConnection) {
  Harness s(with_idle_timeout(1000ms));
  RawClient c(s.port());
  ASSERT_TRUE(c.send(kRead));
  ASSERT_EQ(c.reply(), kReadReply);
  set_limits(s, {32, 2000ms, 60s});
  // Its timer was armed for the old deadline: it fires, finds nothing due, and waits again.
  s.advance(1500ms);
  EXPECT_FALSE(c.closed_by_peer(100ms));
  ASSERT_TRUE(c.send(kRead));
  EXPECT_EQ(c.reply(), kReadReply);
  s.advance(59s);  // 59 s after its last request
  EXPECT_FALSE(c.closed_by_peer(100ms));
  s.advance(1s);
  EXPECT_TRUE(c.closed_by_peer(2000ms));
  EXPECT_EQ(s.stats().idle_timeouts, 1u);
}

TEST(ServerLimits, ShorterFrameTimeoutAppliesToAPartialFrameAlreadyBuffered) {
  ServerOptions o;
  o.frame_timeout = 30s;
  Harness s(o);
  RawClient stalled(s.port());
  // A request and half an MBAP header, then nothing: one send, read at once, so once the answer
  // is back the server holds the partial frame, and its clock has started.
  Bytes stall = kRead;
  stall.insert(stall.end(), {0x00, 0x01, 0x00});
  ASSERT_TRUE(stalled.send(stall));
  ASSERT_EQ(stalled.reply(), kReadReply);
  s.advance(100ms);
  set_limits(s, {32, 300ms, 60s});
  // 300 ms after its first byte, not 30 s, and not at once.
  EXPECT_FALSE(stalled.closed_by_peer(100ms));
  s.advance(199ms);
  EXPECT_FALSE(stalled.closed_by_peer(100ms));
  s.advance(1ms);
  EXPECT_TRUE(stalled.closed_by_peer(2000ms));
  EXPECT_EQ(s.stats().frame_timeouts, 1u);
}

TEST(ServerLimits, LowerMaxClientsRefusesNewcomersAndDropsNoOne) {
  ServerOptions o;
  o.max_clients = 3;
  Harness s(o);
  RawClient a(s.port());
  RawClient b(s.port());
  RawClient c(s.port());
  ASSERT_TRUE(s.wait_clients(3));
  set_limits(s, {1, o.frame_timeout, o.idle_timeout});
  RawClient refused(s.port());
  EXPECT_TRUE(refused.closed_by_peer(1000ms));
  for (RawClient* client : {&a, &b, &c}) {
    ASSERT_TRUE(client->send(kRead));
    EXPECT_EQ(client->reply(), kReadReply);
  }
  EXPECT_EQ(s.stats().connections_refused, 1u);
  // Raised again: the next newcomer is served beside the three.
  set_limits(s, {5, o.frame_timeout, o.idle_timeout});
  RawClient late(s.port());
  ASSERT_TRUE(late.send(kRead));
  EXPECT_EQ(late.reply(), kReadReply);
  EXPECT_TRUE(s.wait_clients(4));
}

}  // namespace
}  // namespace drivegate::modbus
