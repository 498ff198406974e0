// Connections over loopback TCP: libmodbus's client for the ordinary paths, raw sockets for the
// exact bytes, pipelining, late writes, malformed headers and timeouts.
#include <gtest/gtest.h>
#include <modbus.h>

#include <set>
#include <string>

#include "harness.h"

namespace drivegate::modbus {
namespace {

using namespace test;
using Mode = FakeBackend::Mode;

// A libmodbus client connected to the harness, unit 1.
class Libmodbus {
 public:
  explicit Libmodbus(std::uint16_t port, int unit = 1) : ctx_(modbus_new_tcp("127.0.0.1", port)) {
    modbus_set_slave(ctx_, unit);
    modbus_set_response_timeout(ctx_, 2, 0);
    connected_ = modbus_connect(ctx_) == 0;
  }
  ~Libmodbus() {
    modbus_close(ctx_);
    modbus_free(ctx_);
  }
  modbus_t* operator*() const { return ctx_; }
  bool connected() const { return connected_; }

 private:
  modbus_t* ctx_;
  bool connected_ = false;
};

TEST(Connection, LibmodbusReadsAndWritesEveryFunction) {
  Harness h;
  ASSERT_FALSE(h.listen_error());
  Libmodbus c(h.port());
  ASSERT_TRUE(c.connected());

  ASSERT_EQ(modbus_write_register(*c, 10, 0x1234), 1);
  const std::uint16_t values[] = {1, 2, 3};
  ASSERT_EQ(modbus_write_registers(*c, 11, 3, values), 3);
  std::uint16_t regs[4] = {};
  ASSERT_EQ(modbus_read_registers(*c, 10, 4, regs), 4);
  EXPECT_EQ(regs[0], 0x1234);
  EXPECT_EQ(regs[3], 3);

  h.with_backend([](FakeBackend& b) {
    b.table(Table::input)[5] = 0xBEEF;
    b.table(Table::discrete)[7] = 1;
    return 0;
  });
  ASSERT_EQ(modbus_read_input_registers(*c, 5, 1, regs), 1);
  EXPECT_EQ(regs[0], 0xBEEF);
  std::uint8_t bits[10] = {};
  ASSERT_EQ(modbus_read_input_bits(*c, 0, 10, bits), 10);
  EXPECT_EQ(bits[7], 1);
  EXPECT_EQ(bits[6], 0);

  ASSERT_EQ(modbus_write_bit(*c, 3, 1), 1);
  const std::uint8_t coils[] = {1, 0, 1, 1, 0, 0, 0, 0, 1};
  ASSERT_EQ(modbus_write_bits(*c, 20, 9, coils), 9);
  std::uint8_t all[29] = {};
  ASSERT_EQ(modbus_read_bits(*c, 0, 29, all), 29);
  EXPECT_EQ(all[3], 1);
  EXPECT_EQ(all[20], 1);
  EXPECT_EQ(all[21], 0);
  EXPECT_EQ(all[28], 1);

  const std::uint16_t w[] = {7, 8};
  ASSERT_EQ(modbus_write_and_read_registers(*c, 30, 2, w, 29, 3, regs), 3);
  EXPECT_EQ(regs[0], 0);
  EXPECT_EQ(regs[1], 7);
  EXPECT_EQ(regs[2], 8);
}

TEST(Connection, LibmodbusSeesEveryException) {
  Harness h;
  Libmodbus c(h.port());
  ASSERT_TRUE(c.connected());
  std::uint16_t r[2];
  EXPECT_EQ(modbus_read_registers(*c, 0x0400, 1, r), -1);  // unmapped
  EXPECT_EQ(errno, EMBXILADD);
  modbus_set_slave(*c, 9);  // unknown unit
  EXPECT_EQ(modbus_read_registers(*c, 0, 1, r), -1);
  EXPECT_EQ(errno, EMBXGPATH);
  modbus_set_slave(*c, 1);
  h.with_backend([](FakeBackend& b) {
    b.device_result = Exception::server_device_failure;
    return 0;
  });
  EXPECT_EQ(modbus_write_register(*c, 0, 1), -1);  // the drive refused
  EXPECT_EQ(errno, EMBXSFAIL);
  h.with_backend([](FakeBackend& b) {
    b.device_result = Exception::gateway_target_failed;
    return 0;
  });
  EXPECT_EQ(modbus_write_register(*c, 0, 1), -1);  // the drive did not answer
  EXPECT_EQ(errno, EMBXGTAR);
  const auto s = h.stats();
  EXPECT_EQ(s.exceptions[0x02], 1u);
  EXPECT_EQ(s.exceptions[0x0A], 1u);
  EXPECT_EQ(s.exceptions[0x04], 1u);
  EXPECT_EQ(s.exceptions[0x0B], 1u);
  EXPECT_EQ(s.requests, 4u);
}

TEST(Connection, PipelinedRequestsInOneSegmentAreAllAnswered) {
  Harness h;
  h.with_backend([](FakeBackend& b) {
    b.table(Table::holding)[0] = 0x0102;
    return 0;
  });
  RawClient c(h.port());
  ASSERT_TRUE(c.connected());
  Bytes wire;
  for (std::uint16_t t = 1; t <= 20; ++t)
    wire = wire + request(t, 1, {0x03, 0x00, 0x00, 0x00, 0x01});
  ASSERT_TRUE(c.send(wire));
  for (std::uint16_t t = 1; t <= 20; ++t) {
    EXPECT_EQ(c.reply(), (Bytes{0x00, static_cast<std::uint8_t>(t), 0x00, 0x00, 0x00, 0x05, 0x01,
                                0x03, 0x02, 0x01, 0x02}));
  }
}

TEST(Connection, RequestSplitAtEveryByteIsAnswered) {
  Harness h;
  RawClient c(h.port());
  const Bytes req = request(0x0A0B, 2, {0x04, 0x00, 0x08, 0x00, 0x01});
  for (std::size_t split = 1; split < req.size(); ++split) {
    const auto before = h.stats().bytes_received;
    ASSERT_TRUE(c.send(Bytes(req.begin(), req.begin() + static_cast<long>(split))));
    ASSERT_TRUE(h.received(before + split));  // the server read the first part on its own
    ASSERT_TRUE(c.send(Bytes(req.begin() + static_cast<long>(split), req.end())));
    EXPECT_EQ(c.reply(), (Bytes{0x0A, 0x0B, 0x00, 0x00, 0x00, 0x05, 0x02, 0x04, 0x02, 0x00, 0x00}))
        << "split " << split;
  }
}

TEST(Connection, ALateWriteDoesNotHoldBackLaterReads) {
  Harness h;
  h.with_backend([](FakeBackend& b) {
    b.mode = Mode::deferred;
    return 0;
  });
  RawClient c(h.port());
  ASSERT_TRUE(c.send(request(1, 1, {0x06, 0x00, 0x05, 0x00, 0x2A}) +
                     request(2, 1, {0x03, 0x00, 0x05, 0x00, 0x01})));
  // The read (transaction 2) is answered with the old value while the write waits.
  EXPECT_EQ(c.reply(), (Bytes{0x00, 0x02, 0x00, 0x00, 0x00, 0x05, 0x01, 0x03, 0x02, 0x00, 0x00}));
  ASSERT_TRUE(c.send(request(3, 1, {0x03, 0x00, 0x05, 0x00, 0x01})));
  EXPECT_EQ(c.reply(), (Bytes{0x00, 0x03, 0x00, 0x00, 0x00, 0x05, 0x01, 0x03, 0x02, 0x00, 0x00}));
  EXPECT_FALSE(c.readable(50ms));
  h.with_backend([](FakeBackend& b) {
    b.complete();
    return 0;
  });
  EXPECT_EQ(c.reply(),
            (Bytes{0x00, 0x01, 0x00, 0x00, 0x00, 0x06, 0x01, 0x06, 0x00, 0x05, 0x00, 0x2A}));
  ASSERT_TRUE(c.send(request(4, 1, {0x03, 0x00, 0x05, 0x00, 0x01})));
  EXPECT_EQ(c.reply(), (Bytes{0x00, 0x04, 0x00, 0x00, 0x00, 0x05, 0x01, 0x03, 0x02, 0x00, 0x2A}));
}

// Pass-through (Backend::forwards): a unit's every request, a function the server does not know
// included, is handed on as it is and answered later with the device's reply PDU, in its own
// transaction, while the other units' reads go on.
TEST(Connection, APassThroughUnitIsAnsweredWithTheDevicesOwnReply) {
  Harness h;
  RawClient c(h.port());
  ASSERT_TRUE(c.send(request(0x0101, 5, {0x03, 0x00, 0x6B, 0x00, 0x03}) +
                     request(0x0102, 5, {0x41, 0x12}) +
                     request(0x0103, 1, {0x03, 0x00, 0x00, 0x00, 0x01})));
  // Unit 1's read is not held back by the two forwarded requests.
  EXPECT_EQ(c.reply(), (Bytes{0x01, 0x03, 0x00, 0x00, 0x00, 0x05, 0x01, 0x03, 0x02, 0x00, 0x00}));
  ASSERT_TRUE(h.eventually([&h] { return h.source().forwarded.size() == 2; }));
  EXPECT_EQ(h.with_backend([](FakeBackend& b) { return b.forwarded; }),
            (std::vector<Bytes>{{0x03, 0x00, 0x6B, 0x00, 0x03}, {0x41, 0x12}}));
  EXPECT_FALSE(c.readable(50ms));
  h.with_backend([](FakeBackend& b) {
    // Application Protocol 6.3's example reply; then the device's own exception to 0x41.
    b.complete_forward({0x03, 0x06, 0x02, 0x2B, 0x00, 0x00, 0x00, 0x64});
    b.complete_forward({0xC1, 0x01});
    return 0;
  });
  EXPECT_EQ(c.reply(), (Bytes{0x01, 0x01, 0x00, 0x00, 0x00, 0x09, 0x05, 0x03, 0x06, 0x02, 0x2B,
                              0x00, 0x00, 0x00, 0x64}));
  EXPECT_EQ(c.reply(), (Bytes{0x01, 0x02, 0x00, 0x00, 0x00, 0x03, 0x05, 0xC1, 0x01}));
}

// A client pipelining more forwarded reads than the connection's pending slots: the ones past the
// cap wait in the buffer, as writes do, and every one is answered in turn once the device's
// replies come; nothing is dropped, and the server never takes a slot it does not have.
TEST(Connection, PipelinedForwardsPastTheSlotCapWaitAndAreAllAnswered) {
  ServerOptions o;
  o.max_pending_writes = 2;
  Harness h(o);
  RawClient c(h.port());
  Bytes wire;
  for (std::uint16_t t = 1; t <= 6; ++t)
    wire = wire + request(t, 5, {0x03, 0x00, 0x00, 0x00, 0x01});
  ASSERT_TRUE(c.send(wire));
  for (std::uint16_t t = 1; t <= 6; ++t) {
    ASSERT_TRUE(h.eventually([&h] { return !h.source().forwards_pending.empty(); })) << t;
    EXPECT_LE(h.with_backend([](FakeBackend& b) { return b.forwards_pending.size(); }), 2u);
    h.with_backend([](FakeBackend& b) {
      b.complete_forward({0x03, 0x02, 0x12, 0x34});
      return 0;
    });
    EXPECT_EQ(c.reply(), (Bytes{0x00, static_cast<std::uint8_t>(t), 0x00, 0x00, 0x00, 0x05, 0x05,
                                0x03, 0x02, 0x12, 0x34}))
        << t;
  }
}

TEST(Connection, APassThroughRequestTheDeviceMissedIs0x0BAndOneBeyondTheAccessIs01) {
  ServerOptions options;
  options.listeners.front().policy.access = AccessLevel::read;
  Harness h(options);
  RawClient c(h.port());
  ASSERT_TRUE(c.send(request(1, 5, {0x06, 0x00, 0x01, 0x00, 0x02})));
  EXPECT_EQ(c.reply(), (Bytes{0x00, 0x01, 0x00, 0x00, 0x00, 0x03, 0x05, 0x86, 0x01}));
  EXPECT_EQ(h.stats().writes_denied, 1u);
  ASSERT_TRUE(c.send(request(2, 5, {0x03, 0x00, 0x01, 0x00, 0x01})));
  ASSERT_TRUE(h.eventually([&h] { return h.source().forwards_pending.size() == 1; }));
  h.with_backend([](FakeBackend& b) {
    b.complete_forward({}, Exception::gateway_target_failed);
    return 0;
  });
  EXPECT_EQ(c.reply(), (Bytes{0x00, 0x02, 0x00, 0x00, 0x00, 0x03, 0x05, 0x83, 0x0B}));
}

// Application Protocol 6.17 over TCP: an unmapped read range is answered 0x97 0x02 at once and
// the write never reaches the backend; a good one is written, then read.
TEST(Connection, ReadWriteWithAnUnmappedReadRangeIsRefusedBeforeTheWrite) {
  Harness h;
  h.with_backend([](FakeBackend& b) {
    b.mode = Mode::deferred;  // a write that started would be left pending: no reply at all
    return 0;
  });
  RawClient c(h.port());
  // Read 0x0400 x 1 (the hole), write 0x0010 = 0x1234.
  ASSERT_TRUE(c.send(
      request(7, 1, {0x17, 0x04, 0x00, 0x00, 0x01, 0x00, 0x10, 0x00, 0x01, 0x02, 0x12, 0x34})));
  EXPECT_EQ(c.reply(), (Bytes{0x00, 0x07, 0x00, 0x00, 0x00, 0x03, 0x01, 0x97, 0x02}));
  EXPECT_EQ(h.with_backend([](FakeBackend& b) { return b.writes.size(); }), 0u);
  EXPECT_EQ(h.with_backend([](FakeBackend& b) { return b.table(Table::holding)[0x10]; }), 0);

  // The same write with a readable range goes to the device and is answered once it completed.
  ASSERT_TRUE(c.send(
      request(8, 1, {0x17, 0x00, 0x10, 0x00, 0x01, 0x00, 0x10, 0x00, 0x01, 0x02, 0x12, 0x34})));
  ASSERT_TRUE(h.eventually([&h] { return !h.source().pending.empty(); }));
  ASSERT_EQ(h.with_backend([](FakeBackend& b) { return b.pending.size(); }), 1u);
  EXPECT_FALSE(c.readable(50ms));  // the read waits for the write
  h.with_backend([](FakeBackend& b) {
    b.complete();
    return 0;
  });
  EXPECT_EQ(c.reply(), (Bytes{0x00, 0x08, 0x00, 0x00, 0x00, 0x05, 0x01, 0x17, 0x02, 0x12, 0x34}));
  EXPECT_EQ(h.with_backend([](FakeBackend& b) { return b.writes.size(); }), 1u);
}

TEST(Connection, AtTheWriteCapItStopsReadingUntilAWriteCompletes) {
  ServerOptions o;
  o.max_pending_writes = 2;
  Harness h(o);
  h.with_backend([](FakeBackend& b) {
    b.mode = Mode::deferred;
    return 0;
  });
  RawClient c(h.port());
  ASSERT_TRUE(c.send(request(1, 1, {0x06, 0x00, 0x01, 0x00, 0x01}) +
                     request(2, 1, {0x06, 0x00, 0x02, 0x00, 0x02}) +
                     request(3, 1, {0x06, 0x00, 0x03, 0x00, 0x03}) +
                     request(4, 1, {0x03, 0x00, 0x01, 0x00, 0x01})));
  EXPECT_FALSE(c.readable(100ms));  // two writes wait; the third and the read are held
  EXPECT_EQ(h.with_backend([](FakeBackend& b) { return b.pending.size(); }), 2u);
  h.with_backend([](FakeBackend& b) {
    b.complete();
    return 0;
  });
  EXPECT_EQ(c.reply(),
            (Bytes{0x00, 0x01, 0x00, 0x00, 0x00, 0x06, 0x01, 0x06, 0x00, 0x01, 0x00, 0x01}));
  EXPECT_EQ(c.reply(), (Bytes{0x00, 0x04, 0x00, 0x00, 0x00, 0x05, 0x01, 0x03, 0x02, 0x00, 0x01}));
  EXPECT_EQ(h.with_backend([](FakeBackend& b) { return b.pending.size(); }), 2u);
  h.with_backend([](FakeBackend& b) {
    b.complete();
    b.complete(Exception::gateway_target_failed);
    return 0;
  });
  // Both completed before the connection ran again: their replies may leave in either order.
  const std::set<Bytes> replies{c.reply(), c.reply()};
  EXPECT_EQ(replies, (std::set<Bytes>{
                         {0x00, 0x02, 0x00, 0x00, 0x00, 0x06, 0x01, 0x06, 0x00, 0x02, 0x00, 0x02},
                         {0x00, 0x03, 0x00, 0x00, 0x00, 0x03, 0x01, 0x86, 0x0B}}));
}

// A client that is gone (its connection reset) before its write settled cannot be told: the
// write's result is counted (writes_unanswered) and logged, nothing is sent, and the next client
// is served as usual.
TEST(Connection, AWriteCompletingAfterItsClientWasResetIsCountedNotDropped) {
  Harness h;
  h.with_backend([](FakeBackend& b) {
    b.mode = Mode::deferred;
    return 0;
  });
  {
    RawClient c(h.port());
    ASSERT_TRUE(c.send(request(1, 1, {0x06, 0x00, 0x01, 0x00, 0x01})));
    ASSERT_TRUE(h.wait_clients(1));
    ASSERT_TRUE(h.eventually([&h] { return !h.source().pending.empty(); }));
    c.reset();
  }
  ASSERT_TRUE(h.wait_clients(0));
  EXPECT_EQ(h.stats().writes_unanswered, 0u);  // not settled yet
  h.with_backend([](FakeBackend& b) {
    b.complete();
    return 0;
  });
  RawClient d(h.port());
  ASSERT_TRUE(d.send(request(9, 1, {0x03, 0x00, 0x01, 0x00, 0x01})));
  EXPECT_EQ(d.reply(), (Bytes{0x00, 0x09, 0x00, 0x00, 0x00, 0x05, 0x01, 0x03, 0x02, 0x00, 0x01}));
  EXPECT_EQ(h.stats().responses, 1u);
  EXPECT_EQ(h.stats().writes_unanswered, 1u);
}

// A client that half-closes (SHUT_WR) right after a write still with its device: the connection
// waits for it, sends its reply, then closes. (The write is not dropped with the connection.)
TEST(Connection, AHalfClosedClientGetsTheReplyToAWriteStillWithItsDevice) {
  Harness h;
  h.with_backend([](FakeBackend& b) {
    b.mode = Mode::deferred;
    return 0;
  });
  RawClient c(h.port());
  ASSERT_TRUE(c.send(request(4, 1, {0x06, 0x00, 0x00, 0x00, 0x01})));
  c.shutdown_write();
  ASSERT_TRUE(h.eventually([&h] { return !h.source().pending.empty(); }));
  EXPECT_FALSE(c.closed_by_peer(50ms));  // still open, waiting for the write
  EXPECT_EQ(h.stats().connections_active, 1u);
  h.with_backend([](FakeBackend& b) {
    b.complete();
    return 0;
  });
  EXPECT_EQ(c.reply(),
            (Bytes{0x00, 0x04, 0x00, 0x00, 0x00, 0x06, 0x01, 0x06, 0x00, 0x00, 0x00, 0x01}));
  EXPECT_TRUE(c.closed_by_peer(1000ms));
  EXPECT_TRUE(h.wait_clients(0));
  EXPECT_EQ(h.stats().writes_unanswered, 0u);
}

// --- MBAP outcomes over TCP (Implementation Guide V1.0b, 3.1.3) ----------------------------

struct MbapCase {
  const char* name;
  Bytes wire;
  bool closes;
};
void PrintTo(const MbapCase& c, std::ostream* os) {
  *os << c.name;
}

class ConnectionMbap : public ::testing::TestWithParam<MbapCase> {};

TEST_P(ConnectionMbap, OutcomeAndOtherClientsUndisturbed) {
  Harness h;
  Libmodbus other(h.port());
  ASSERT_TRUE(other.connected());
  RawClient c(h.port());
  ASSERT_TRUE(c.send(GetParam().wire));
  if (GetParam().closes) {
    EXPECT_TRUE(c.closed_by_peer(500ms));
  } else {
    const Bytes r = c.reply();
    ASSERT_EQ(r.size(), 9u);
    EXPECT_EQ(r[7], 0xC1);  // function 0x41 is not served: exception 01
    EXPECT_EQ(r[8], 0x01);
    EXPECT_FALSE(c.closed_by_peer(50ms));
  }
  std::uint16_t v;
  EXPECT_EQ(modbus_read_registers(*other, 0, 1, &v), 1);
  EXPECT_EQ(h.clients(), GetParam().closes ? 1u : 2u);
}

// The same bytes in two segments, split after every byte: the outcome does not depend on how TCP
// cut the stream (a closing header is judged as soon as its deciding bytes are in; the rest of a
// split frame that the server already refused may find the connection gone).
TEST_P(ConnectionMbap, SameOutcomeWhenSplitAtEveryByte) {
  Harness h;
  Libmodbus other(h.port());
  ASSERT_TRUE(other.connected());
  const Bytes& wire = GetParam().wire;
  for (std::size_t split = 1; split < wire.size(); ++split) {
    RawClient c(h.port());
    ASSERT_TRUE(c.connected());
    const auto before = h.stats().bytes_received;
    ASSERT_TRUE(c.send(Bytes(wire.begin(), wire.begin() + static_cast<long>(split))));
    ASSERT_TRUE(h.received(before + split)) << "split " << split;
    const bool sent = c.send(Bytes(wire.begin() + static_cast<long>(split), wire.end()));
    if (GetParam().closes) {
      EXPECT_TRUE(c.closed_by_peer(500ms)) << "split " << split;
    } else {
      ASSERT_TRUE(sent) << "split " << split;
      const Bytes r = c.reply();
      ASSERT_EQ(r.size(), 9u) << "split " << split;
      EXPECT_EQ(r[7], 0xC1) << "split " << split;
      EXPECT_EQ(r[8], 0x01) << "split " << split;
    }
  }
  std::uint16_t v;
  EXPECT_EQ(modbus_read_registers(*other, 0, 1, &v), 1);
  ASSERT_TRUE(h.wait_clients(1));
  EXPECT_EQ(h.stats().malformed, GetParam().closes ? wire.size() - 1 : 0u);
}

Bytes header(std::uint16_t protocol, std::uint16_t length) {
  return {0x00,
          0x01,
          static_cast<std::uint8_t>(protocol >> 8),
          static_cast<std::uint8_t>(protocol),
          static_cast<std::uint8_t>(length >> 8),
          static_cast<std::uint8_t>(length),
          0x01};
}

INSTANTIATE_TEST_SUITE_P(
    Table, ConnectionMbap,
    ::testing::Values(MbapCase{"protocol_id_1", header(1, 6) + Bytes{0x03, 0, 0, 0, 1}, true},
                      MbapCase{"length_0", header(0, 0), true},
                      MbapCase{"length_1", header(0, 1), true},
                      MbapCase{"length_254", header(0, 254) + Bytes{0x41} + Bytes(252, 0x00),
                               false},
                      MbapCase{"length_255", header(0, 255) + Bytes{0x41} + Bytes(253, 0x00), true},
                      MbapCase{"length_65535", header(0, 65535) + Bytes{0x03, 0, 0, 0, 1}, true}),
    [](const auto& p) { return std::string(p.param.name); });

TEST(Connection, RequestLongerThanAnnouncedIsAnsweredThenTheRestIsJudged) {
  Harness h;
  Libmodbus other(h.port());
  ASSERT_TRUE(other.connected());
  RawClient c(h.port());
  // Length 6, then four more bytes: the reply goes out, then "AA BB CC DD" is read as the next
  // header, whose protocol id (CC DD) is not 0: the connection closes.
  ASSERT_TRUE(
      c.send(request(1, 1, {0x03, 0x00, 0x00, 0x00, 0x01}) + Bytes{0xAA, 0xBB, 0xCC, 0xDD}));
  EXPECT_EQ(c.reply(), (Bytes{0x00, 0x01, 0x00, 0x00, 0x00, 0x05, 0x01, 0x03, 0x02, 0x00, 0x00}));
  EXPECT_TRUE(c.closed_by_peer(500ms));
  EXPECT_EQ(h.stats().malformed, 1u);
  std::uint16_t v;
  EXPECT_EQ(modbus_read_registers(*other, 0, 1, &v), 1);
  EXPECT_EQ(h.clients(), 1u);
}

// Several requests in one segment followed by a malformed header: every request before it is
// answered, in order, then the connection closes; another client notices nothing.
TEST(Connection, SeveralRequestsThenAMalformedHeaderInOneSegment) {
  Harness h;
  Libmodbus other(h.port());
  ASSERT_TRUE(other.connected());
  RawClient c(h.port());
  ASSERT_TRUE(c.send(request(1, 1, {0x03, 0x00, 0x00, 0x00, 0x01}) +
                     request(2, 1, {0x04, 0x00, 0x00, 0x00, 0x01}) + request(3, 1, {0x41}) +
                     header(0, 0)));
  EXPECT_EQ(c.reply(), (Bytes{0x00, 0x01, 0x00, 0x00, 0x00, 0x05, 0x01, 0x03, 0x02, 0x00, 0x00}));
  EXPECT_EQ(c.reply(), (Bytes{0x00, 0x02, 0x00, 0x00, 0x00, 0x05, 0x01, 0x04, 0x02, 0x00, 0x00}));
  EXPECT_EQ(c.reply(), (Bytes{0x00, 0x03, 0x00, 0x00, 0x00, 0x03, 0x01, 0xC1, 0x01}));
  EXPECT_TRUE(c.closed_by_peer(500ms));
  EXPECT_EQ(h.stats().malformed, 1u);
  std::uint16_t v;
  EXPECT_EQ(modbus_read_registers(*other, 0, 1, &v), 1);
  EXPECT_EQ(h.clients(), 1u);
}

// A request and, in the same send, the first `n` bytes of the next: once the answer is back the
// server holds the partial frame, and its frame timeout runs from that moment of its clock.
Bytes answered_then_partial(const Bytes& next, std::size_t n) {
  Bytes out = request(9, 1, {0x03, 0x00, 0x00, 0x00, 0x01});
  out.insert(out.end(), next.begin(), next.begin() + static_cast<long>(n));
  return out;
}

TEST(Connection, HalfFrameThenStallIsClosedAfterFrameTimeoutWithoutDelayingOthers) {
  ServerOptions o;
  o.frame_timeout = 300ms;
  Harness h(o);
  RawClient stalled(h.port());
  Libmodbus other(h.port());
  ASSERT_TRUE(other.connected());
  ASSERT_TRUE(stalled.send(answered_then_partial(request(1, 1, {0x03, 0, 0, 0, 1}), 3)));
  ASSERT_EQ(stalled.reply().size(), 11u);
  for (int i = 0; i < 3; ++i) {  // 299 ms of the server's time: the other client is served
    std::uint16_t v;
    ASSERT_EQ(modbus_read_registers(*other, 0, 1, &v), 1);
    h.advance(i < 2 ? 100ms : 99ms);
  }
  EXPECT_FALSE(stalled.closed_by_peer(100ms));
  h.advance(1ms);
  EXPECT_TRUE(stalled.closed_by_peer(2000ms));
  std::uint16_t v;
  EXPECT_EQ(modbus_read_registers(*other, 0, 1, &v), 1);
  EXPECT_EQ(h.stats().frame_timeouts, 1u);
}

TEST(Connection, ATrickleOfBytesDoesNotExtendTheFrameTimeout) {
  ServerOptions o;
  o.frame_timeout = 300ms;
  Harness h(o);
  RawClient c(h.port());
  const Bytes req = request(1, 1, {0x10, 0x00, 0x00, 0x00, 0x02, 0x04, 0, 0, 0, 0});
  ASSERT_TRUE(c.send(answered_then_partial(req, 1)));
  ASSERT_EQ(c.reply().size(), 11u);
  // A byte every 40 ms of the server's time, never the last: 280 ms after the first, still open.
  for (std::size_t i = 1; i <= 7; ++i) {
    ASSERT_TRUE(c.send({req[i]}));
    h.advance(40ms);
  }
  EXPECT_FALSE(c.closed_by_peer(100ms));
  ASSERT_TRUE(c.send({req[8]}));
  h.advance(20ms);  // 300 ms after the first byte, 20 ms after the last
  EXPECT_TRUE(c.closed_by_peer(2000ms));
  EXPECT_EQ(h.stats().frame_timeouts, 1u);
}

TEST(Connection, IdleClientIsClosedAfterIdleTimeout) {
  ServerOptions o;
  o.idle_timeout = 300ms;
  Harness h(o);
  RawClient busy(h.port());
  RawClient idle(h.port());
  // `busy` asks every 50 ms and stays; `idle` asks once and is closed 300 ms after that.
  ASSERT_TRUE(idle.send(request(1, 1, {0x03, 0x00, 0x00, 0x00, 0x01})));
  EXPECT_EQ(idle.reply().size(), 11u);
  for (int i = 1; i <= 10; ++i) {
    ASSERT_TRUE(busy.send(request(1, 1, {0x03, 0x00, 0x00, 0x00, 0x01})));
    ASSERT_EQ(busy.reply().size(), 11u);
    h.advance(50ms);
    if (i == 5) {
      EXPECT_FALSE(idle.closed_by_peer(100ms)) << "250 ms after its request";
    }
    if (i == 6) {
      EXPECT_TRUE(idle.closed_by_peer(2000ms)) << "300 ms after its request";
    }
  }
  EXPECT_FALSE(busy.closed_by_peer(10ms));
  EXPECT_EQ(h.stats().idle_timeouts, 1u);
}

TEST(Connection, AClientThatStopsSendingStillGetsItsReplies) {
  Harness h;
  RawClient c(h.port());
  ASSERT_TRUE(c.send(request(1, 1, {0x03, 0x00, 0x00, 0x00, 0x01}) +
                     request(2, 1, {0x04, 0x00, 0x00, 0x00, 0x01})));
  c.shutdown_write();
  EXPECT_EQ(c.reply(), (Bytes{0x00, 0x01, 0x00, 0x00, 0x00, 0x05, 0x01, 0x03, 0x02, 0x00, 0x00}));
  EXPECT_EQ(c.reply(), (Bytes{0x00, 0x02, 0x00, 0x00, 0x00, 0x05, 0x01, 0x04, 0x02, 0x00, 0x00}));
  EXPECT_TRUE(c.closed_by_peer(1000ms));
  EXPECT_TRUE(h.wait_clients(0));
}

TEST(Connection, DeviceIdentificationOverTcp) {
  ServerOptions o;
  o.identity = {"drivegate", "drivegated", "0.1.0"};
  Harness h(o);
  RawClient c(h.port());
  ASSERT_TRUE(c.send(request(5, 1, {0x2B, 0x0E, 0x04, 0x02})));
  EXPECT_EQ(c.reply(), (Bytes{0x00, 0x05, 0x00, 0x00, 0x00, 0x0F, 0x01, 0x2B, 0x0E, 0x04, 0x81,
                              0x00, 0x00, 0x01, 0x02, 0x05, '0',  '.',  '1',  '.',  '0'}));
}

}  // namespace
}  // namespace drivegate::modbus
