// The acceptor: client cap, descriptor hygiene, shutdown, addresses.
#include <dirent.h>
#include <gtest/gtest.h>
#include <modbus.h>

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
  o.host = "not-an-address";
  Harness h(o);
  EXPECT_EQ(h.listen_error(), std::errc::invalid_argument);
}

TEST(Server, ListensOnIpv6Loopback) {
  ServerOptions o;
  o.host = "[::1]";
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

// Issue 8: 10,000 connect / disconnect cycles leak no descriptor.
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
  ASSERT_TRUE(h.wait_clients(0));
  EXPECT_EQ(open_descriptors(), before);
  EXPECT_EQ(h.stats().connections_active, 0u);
}

TEST(Server, CloseDisconnectsEveryClientAndLeavesNothingRunning) {
  boost::asio::io_context io;
  FakeBackend backend;
  backend.mode = FakeBackend::Mode::deferred;
  auto log = std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::null_sink_st>());
  ServerOptions o;
  o.host = "127.0.0.1";
  o.port = 0;
  auto server = std::make_unique<Server>(io, backend, o, log);
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

}  // namespace
}  // namespace drivegate::modbus
