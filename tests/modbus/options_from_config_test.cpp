// The Modbus server's options made from the configuration's plain data: the Modbus TCP
// listeners only, in the file's order, each with its policy and TLS files, and [server]'s limits.
#include "modbus/options_from_config.h"

#include <gtest/gtest.h>

namespace drivegate::modbus {
namespace {

TEST(OptionsFromConfig, TheModbusTcpListenersWithTheirPoliciesAndServerLimits) {
  Config c;
  c.server.max_clients = 7;
  c.server.idle_timeout = Millis(1234);
  c.server.frame_timeout = Millis(56);
  ListenerConfig plain;
  plain.host = "127.0.0.1";
  plain.port = 1502;
  plain.policy.access = AccessLevel::read;
  plain.policy.word_order = WordOrder::little;
  plain.policy.max_clients = 3;
  std::string error;
  plain.policy.allow = {*net::parse_address_range("192.168.1.0/24", error)};
  ListenerConfig rtu = plain;
  rtu.framing = ListenerFraming::rtu;  // the serial slave's, not the server's
  ListenerConfig tls;
  tls.host = "::1";
  tls.port = 802;
  tls.policy.tls = ListenerTlsConfig{
      .cert = "/c.pem", .key = "/k.pem", .ca = "/ca.pem", .roles = {{"op", AccessLevel::operate}}};
  tls.policy.handshakes = net::RateLimit::per_second_in_bursts_of_two(9);
  c.listeners = {plain, rtu, tls};

  const ServerOptions o = server_options(c);
  EXPECT_EQ(o.max_clients, 7u);
  EXPECT_EQ(o.idle_timeout, std::chrono::milliseconds(1234));
  EXPECT_EQ(o.frame_timeout, std::chrono::milliseconds(56));
  ASSERT_EQ(o.listeners.size(), 2u);
  EXPECT_EQ(o.listeners[0].name(), "127.0.0.1:1502");
  EXPECT_EQ(o.listeners[0].policy.access, AccessLevel::read);
  EXPECT_EQ(o.listeners[0].policy.word_order, WordOrder::little);
  EXPECT_EQ(o.listeners[0].policy.max_clients, std::optional<std::size_t>(3));
  EXPECT_EQ(o.listeners[0].policy.allow, plain.policy.allow);
  EXPECT_FALSE(o.listeners[0].policy.tls);
  EXPECT_EQ(o.listeners[1].name(), "[::1]:802 (TLS)");
  EXPECT_EQ(o.listeners[1].name(), listener_name(tls));  // one name in the log and the config
  ASSERT_TRUE(o.listeners[1].policy.tls);
  EXPECT_EQ(o.listeners[1].policy.tls->cert, "/c.pem");
  EXPECT_EQ(o.listeners[1].policy.tls->key, "/k.pem");
  EXPECT_EQ(o.listeners[1].policy.tls->ca, "/ca.pem");
  EXPECT_EQ(o.listeners[1].policy.tls->roles.at("op"), AccessLevel::operate);
  EXPECT_EQ(o.listeners[1].policy.handshakes.per_second, 9u);
  EXPECT_EQ(server_limits(c.server), o.limits());
}

}  // namespace
}  // namespace drivegate::modbus
