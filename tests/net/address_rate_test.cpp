// The per-address token bucket behind the TLS handshake and HTTP request limits,
// on a clock the test sets.
#include "net/address_rate.h"

#include <gtest/gtest.h>

namespace drivegate::net {
namespace {

using namespace std::chrono_literals;
using Clock = AddressRate::Clock;
namespace ip = boost::asio::ip;

const Clock::time_point t0{std::chrono::hours(1)};

TEST(AddressRate, ABurstThenThePerSecondRate) {
  AddressRate r({2, 4});
  const auto a = ip::make_address("192.0.2.1");
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(r.admit(a, t0)) << i;
  EXPECT_FALSE(r.admit(a, t0));
  EXPECT_EQ(r.next_token(a, t0), t0 + 500ms);
  EXPECT_FALSE(r.admit(a, t0 + 499ms));
  EXPECT_TRUE(r.admit(a, t0 + 500ms));
  EXPECT_FALSE(r.admit(a, t0 + 500ms));
  // Another address has its own bucket.
  EXPECT_TRUE(r.admit(ip::make_address("192.0.2.2"), t0));
  // Saved up to the burst, never more.
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(r.admit(a, t0 + 60s)) << i;
  EXPECT_FALSE(r.admit(a, t0 + 60s));
}

// What cost more than a token (a large response) is charged after the fact: the address waits
// until its balance, below zero now, is back to one token.
TEST(AddressRate, ACostlyRequestIsChargedAndTheNextWaitsForIt) {
  AddressRate r({10, 20});
  const auto a = ip::make_address("192.0.2.1");
  ASSERT_TRUE(r.admit(a, t0));
  r.charge(a, 24, t0);  // 19 left, 24 more taken: -5
  EXPECT_FALSE(r.admit(a, t0));
  EXPECT_EQ(r.next_token(a, t0), t0 + 600ms);
  EXPECT_FALSE(r.admit(a, t0 + 599ms));
  EXPECT_TRUE(r.admit(a, t0 + 600ms));
  EXPECT_TRUE(r.admit(ip::make_address("192.0.2.2"), t0)) << "another address is not charged";
  AddressRate unlimited({0, 1});
  unlimited.charge(a, 1000, t0);
  EXPECT_TRUE(unlimited.admit(a, t0));
}

TEST(AddressRate, ZeroIsUnlimited) {
  AddressRate r({0, 1});
  const auto a = ip::make_address("192.0.2.1");
  for (int i = 0; i < 10000; ++i) ASSERT_TRUE(r.admit(a, t0));
  EXPECT_EQ(r.tracked(), 0u);
  EXPECT_EQ(r.next_token(a, t0), t0);
}

// One IPv6 host can use any address of its /64: the prefix is the client. IPv4-mapped IPv6 is
// the IPv4 address.
TEST(AddressRate, IPv6CountsByItsSlash64) {
  AddressRate r({1, 1});
  EXPECT_TRUE(r.admit(ip::make_address("2001:db8:1:2::1"), t0));
  EXPECT_FALSE(r.admit(ip::make_address("2001:db8:1:2:ffff::9"), t0));
  EXPECT_TRUE(r.admit(ip::make_address("2001:db8:1:3::1"), t0));
  EXPECT_TRUE(r.admit(ip::make_address("192.0.2.7"), t0));
  EXPECT_FALSE(r.admit(ip::make_address("::ffff:192.0.2.7"), t0));
}

// Past the bound, full buckets are forgotten first; if none is, the newcomers share one.
TEST(AddressRate, TheTableIsBounded) {
  AddressRate r({1, 1}, 3);
  const auto addr = [](int i) {
    return ip::make_address_v4(0xC0000200u + static_cast<unsigned>(i));
  };
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(r.admit(addr(i), t0));
  EXPECT_EQ(r.tracked(), 3u);
  // All three spent: addresses 3 and 4 share the overflow bucket.
  EXPECT_TRUE(r.admit(addr(3), t0));
  EXPECT_FALSE(r.admit(addr(4), t0));
  EXPECT_EQ(r.tracked(), 3u);
  // A second later every bucket is full again: forgotten, and the newcomer gets its own.
  EXPECT_TRUE(r.admit(addr(5), t0 + 1s));
  EXPECT_EQ(r.tracked(), 1u);
}

TEST(AddressRate, ANewLimitAppliesAtOnce) {
  AddressRate r({1, 1});
  const auto a = ip::make_address("192.0.2.1");
  EXPECT_TRUE(r.admit(a, t0));
  EXPECT_FALSE(r.admit(a, t0));
  r.set_limit({0, 1});
  EXPECT_TRUE(r.admit(a, t0));
}

}  // namespace
}  // namespace drivegate::net
