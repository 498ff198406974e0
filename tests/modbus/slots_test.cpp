// Connection slots per listener: read clients cannot take an operate listener's slots,
// and a full listener closes its longest-idle read-only client for a newcomer before refusing
// anyone. Operate and maintain clients never give way.
#include <gtest/gtest.h>

#include "harness.h"

namespace drivegate::modbus::slots_test {
namespace {

using test::Bytes;
using test::Harness;
using test::RawClient;
using test::request;
using namespace std::chrono_literals;

const Bytes kRead = request(1, 1, {0x03, 0x00, 0x00, 0x00, 0x01});
constexpr std::size_t kReadReplySize = 11;

ServerOptions with(std::vector<ListenerPolicy> policies, std::size_t server_max = 32) {
  ServerOptions o;
  o.max_clients = server_max;
  o.listeners.clear();
  for (auto& p : policies) {
    ListenerOptions l;
    l.policy = std::move(p);
    o.listeners.push_back(std::move(l));
  }
  return o;
}

bool served(RawClient& c) {
  return c.send(kRead) && c.reply().size() == kReadReplySize;
}

// The case: 32 idle clients fill a read-only listener; the PLC on the operate listener
// is served at once, and so is a newcomer on the read listener, in place of the idlest.
TEST(ListenerSlots, IdleReadClientsNeitherLockOutThePlcNorEachOther) {
  Harness h(with({{.access = AccessLevel::read, .max_clients = 32},
                  {.access = AccessLevel::operate, .max_clients = 2}}));
  std::vector<std::unique_ptr<RawClient>> idle;
  for (int i = 0; i < 32; ++i) {
    idle.push_back(std::make_unique<RawClient>(h.port(0)));
    ASSERT_TRUE(served(*idle.back()));  // each asked once, then went quiet
    h.advance(1ms);                     // the first the idlest, the last the most recent
  }
  ASSERT_TRUE(h.wait_clients(32));
  RawClient plc(h.port(1));
  EXPECT_TRUE(served(plc));  // its own slots: nothing had to give way
  EXPECT_EQ(h.stats().connections_evicted, 0u);

  // One more read client: the one idle longest (the first) gives way, nobody is refused.
  ASSERT_TRUE(served(*idle[5]));  // no longer among the idlest
  RawClient newcomer(h.port(0));
  EXPECT_TRUE(served(newcomer));
  EXPECT_TRUE(idle[0]->closed_by_peer(1000ms));
  EXPECT_TRUE(served(*idle[5]));
  EXPECT_TRUE(served(*idle[1]));
  const auto s = h.stats();
  EXPECT_EQ(s.connections_evicted, 1u);
  EXPECT_EQ(s.connections_refused, 0u);
  EXPECT_EQ(h.on_io([&] { return h.server().listener_stats(0).connections_evicted; }), 1u);
  EXPECT_TRUE(served(plc));
}

// A full operate listener refuses the newcomer and keeps every client it has.
TEST(ListenerSlots, OperateClientsNeverGiveWay) {
  Harness h(with({{.access = AccessLevel::operate, .max_clients = 2}}));
  RawClient a(h.port());
  RawClient b(h.port());
  ASSERT_TRUE(served(a));
  ASSERT_TRUE(served(b));
  RawClient extra(h.port());
  EXPECT_TRUE(extra.closed_by_peer(1000ms));
  EXPECT_TRUE(served(a));
  EXPECT_TRUE(served(b));
  EXPECT_EQ(h.stats().connections_refused, 1u);
  EXPECT_EQ(h.stats().connections_evicted, 0u);
  EXPECT_EQ(h.on_io([&] { return h.server().listener_stats(0).connections_refused; }), 1u);
}

// A read client in the middle of a request (a partial frame) is not idle: it keeps its slot.
TEST(ListenerSlots, AReadClientMidRequestKeepsItsSlot) {
  Harness h(with({{.access = AccessLevel::read, .max_clients = 1}}));
  RawClient busy(h.port());
  ASSERT_TRUE(served(busy));
  const auto before = h.stats().bytes_received;
  ASSERT_TRUE(busy.send({0x00, 0x02, 0x00}));  // half a header
  ASSERT_TRUE(h.received(before + 3));
  RawClient extra(h.port());
  EXPECT_TRUE(extra.closed_by_peer(1000ms));
  ASSERT_TRUE(busy.send({0x00, 0x00, 0x06, 0x01, 0x03, 0x00, 0x00, 0x00, 0x01}));
  EXPECT_EQ(busy.reply().size(), kReadReplySize);
}

// Without a max_clients of its own a listener has [server] max_clients slots, of its own too:
// one listener's clients never count against another's.
TEST(ListenerSlots, ServerMaxClientsIsEachListenersDefault) {
  Harness h(with({{.access = AccessLevel::maintain}, {.access = AccessLevel::maintain}}, 1));
  RawClient a(h.port(0));
  RawClient b(h.port(1));
  EXPECT_TRUE(served(a));
  EXPECT_TRUE(served(b));
  RawClient extra(h.port(0));
  EXPECT_TRUE(extra.closed_by_peer(1000ms));
}

}  // namespace
}  // namespace drivegate::modbus::slots_test
