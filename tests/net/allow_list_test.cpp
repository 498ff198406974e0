// Allow lists: parsing (addresses, CIDR ranges, what is refused and why) and matching, IPv4-mapped
// IPv6 peers included.
#include "net/allow_list.h"

#include <gtest/gtest.h>

namespace drivegate::net {
namespace {

namespace ip = boost::asio::ip;

AddressRange range(std::string_view text) {
  std::string error;
  auto r = parse_address_range(text, error);
  EXPECT_TRUE(r) << text << ": " << error;
  return r.value_or(AddressRange{});
}

std::string refusal(std::string_view text) {
  std::string error;
  EXPECT_FALSE(parse_address_range(text, error)) << text;
  return error;
}

TEST(AllowList, AddressesAreWholeLengthRanges) {
  EXPECT_EQ(range("10.1.3.7").prefix, 32u);
  EXPECT_EQ(range("::1").prefix, 128u);
  EXPECT_EQ(range("10.1.3.7").to_string(), "10.1.3.7");
  EXPECT_EQ(range("10.1.2.0/24").to_string(), "10.1.2.0/24");
}

TEST(AllowList, RangesMatchTheirPrefixOnly) {
  const auto r = range("10.1.2.0/24");
  EXPECT_TRUE(r.contains(ip::make_address("10.1.2.0")));
  EXPECT_TRUE(r.contains(ip::make_address("10.1.2.255")));
  EXPECT_FALSE(r.contains(ip::make_address("10.1.3.0")));
  EXPECT_FALSE(r.contains(ip::make_address("10.1.1.255")));
  const auto odd = range("192.168.0.128/25");
  EXPECT_TRUE(odd.contains(ip::make_address("192.168.0.200")));
  EXPECT_FALSE(odd.contains(ip::make_address("192.168.0.127")));
  const auto v6 = range("fd00:1::/32");
  EXPECT_TRUE(v6.contains(ip::make_address("fd00:1:ffff::9")));
  EXPECT_FALSE(v6.contains(ip::make_address("fd00:2::9")));
  EXPECT_FALSE(v6.contains(ip::make_address("10.1.2.3")));  // other family
}

TEST(AllowList, AnIPv4ClientOnADualStackSocketMatchesIPv4Ranges) {
  const auto mapped = ip::make_address("::ffff:10.1.2.9");
  EXPECT_TRUE(range("10.1.2.0/24").contains(mapped));
  EXPECT_TRUE(range("10.1.2.9").contains(mapped));
  EXPECT_FALSE(range("10.1.3.0/24").contains(mapped));
  // And a mapped address written in the list is the IPv4 address.
  EXPECT_TRUE(range("::ffff:10.1.2.9").contains(ip::make_address("10.1.2.9")));
}

TEST(AllowList, EmptyAllowsEveryoneAndSlashZeroIsEveryoneOfItsFamily) {
  EXPECT_TRUE(allowed({}, ip::make_address("203.0.113.5")));
  EXPECT_TRUE(allows_everyone({}));
  const AllowList any4{range("0.0.0.0/0")};
  EXPECT_TRUE(allowed(any4, ip::make_address("203.0.113.5")));
  EXPECT_FALSE(allowed(any4, ip::make_address("2001:db8::1")));
  EXPECT_TRUE(allows_everyone(any4));
  const AllowList plant{range("10.1.2.0/24"), range("10.1.3.7")};
  EXPECT_FALSE(allows_everyone(plant));
  EXPECT_TRUE(allowed(plant, ip::make_address("10.1.3.7")));
  EXPECT_FALSE(allowed(plant, ip::make_address("10.1.3.8")));
}

TEST(AllowList, MistakesAreRefusedWithTheReason) {
  EXPECT_NE(refusal("10.1.2.5/24").find("bits set beyond /24"), std::string::npos);
  EXPECT_NE(refusal("10.1.2.0/33").find("0..32"), std::string::npos);
  EXPECT_NE(refusal("fd00::/129").find("0..128"), std::string::npos);
  EXPECT_NE(refusal("10.1.2.0/").find("0..32"), std::string::npos);
  EXPECT_NE(refusal("10.1.2.0/2x").find("0..32"), std::string::npos);
  EXPECT_NE(refusal("plc.local").find("not an IPv4 or IPv6 address"), std::string::npos);
  EXPECT_NE(refusal("10.1.2").find("not an IPv4"), std::string::npos);
  EXPECT_NE(refusal("").find("not an IPv4"), std::string::npos);
}

}  // namespace
}  // namespace drivegate::net
