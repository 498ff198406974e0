// [[bus]] port: a device path, tcp://host:port or rfc2217://host:port, and what is refused.
#include "config/port_address.h"

#include <gtest/gtest.h>

namespace drivegate {
namespace {

PortAddress parse(std::string_view text) {
  std::string error;
  auto a = parse_port_address(text, error);
  EXPECT_TRUE(a) << text << ": " << error;
  return a.value_or(PortAddress{});
}

std::string refusal(std::string_view text) {
  std::string error;
  EXPECT_FALSE(parse_port_address(text, error)) << text;
  return error;
}

TEST(PortAddress, EachForm) {
  const auto tty = parse("/dev/serial/by-id/usb-FTDI-if00-port0");
  EXPECT_EQ(tty.kind, PortAddress::Kind::tty);
  EXPECT_EQ(tty.path, "/dev/serial/by-id/usb-FTDI-if00-port0");
  EXPECT_FALSE(tty.network());
  const auto tcp = parse("tcp://10.1.5.20:4001");
  EXPECT_EQ(tcp.kind, PortAddress::Kind::tcp);
  EXPECT_EQ(tcp.host, "10.1.5.20");
  EXPECT_EQ(tcp.port, 4001);
  EXPECT_TRUE(tcp.network());
  const auto named = parse("rfc2217://nport-7.plant:950");
  EXPECT_EQ(named.kind, PortAddress::Kind::rfc2217);
  EXPECT_EQ(named.host, "nport-7.plant");
  const auto v6 = parse("tcp://[fd00::20]:4001");
  EXPECT_EQ(v6.host, "fd00::20");
  EXPECT_EQ(v6.port, 4001);
}

TEST(PortAddress, MistakesSayWhatIsExpected) {
  EXPECT_NE(refusal("tcp://10.1.5.20").find("tcp://host:port"), std::string::npos);
  EXPECT_NE(refusal("tcp://10.1.5.20:0").find("1..65535"), std::string::npos);
  EXPECT_NE(refusal("rfc2217://:4001").find("rfc2217://host:port"), std::string::npos);
  EXPECT_NE(refusal("tcp://h:70000").find("1..65535"), std::string::npos);
  EXPECT_NE(refusal("udp://h:1").find("unknown scheme"), std::string::npos);
  EXPECT_NE(refusal("").find("is empty"), std::string::npos);
}

}  // namespace
}  // namespace drivegate
