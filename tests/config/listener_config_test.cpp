// [[listener]] in drivegate.toml: what is read, the defaults (read-only unless the file says
// otherwise), every mistake named with its line, and the warning for a listener anyone may write
// through.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "config/config_loader.h"
#include "fake_adapter.h"

namespace drivegate {
namespace {

using ::testing::AllOf;
using ::testing::Contains;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::IsEmpty;

constexpr const char* kDevice = R"(
[[bus]]
name = "line1"
port = "/dev/ttyUSB0"

[[device]]
name = "washer"
bus = "line1"
adapter = "fake"
unit_id = 3
)";

class ListenerConfig : public ::testing::Test {
 protected:
  ListenerConfig() { plugins_.add(test::kFakeAdapter); }
  ConfigResult parse(const std::string& listeners) {
    return parse_config(listeners + kDevice, "gw.toml", plugins_);
  }
  std::vector<std::string> errors(const std::string& listeners) {
    auto r = parse(listeners);
    EXPECT_FALSE(r.config.has_value());
    return r.errors;
  }
  PluginRegistry plugins_;
};

TEST_F(ListenerConfig, EveryKeyIsRead) {
  const auto r = parse(R"(
[server]
max_clients = 9

[[listener]]
address = "0.0.0.0:502"
allow = ["10.1.2.0/24", "10.1.3.7", "fd00::/8"]
access = "operate"
word_order = "little"

[[listener]]
address = "[::]:802"
tls = { cert = "/etc/drivegate/tls/server.pem", key = "/etc/drivegate/tls/server.key", ca = "/etc/drivegate/tls/ca.pem" }
roles = { viewer = "read", operator = "operate", engineer = "maintain" }
)");
  ASSERT_TRUE(r.config) << ::testing::PrintToString(r.errors);
  const auto& ls = r.config->listeners;
  ASSERT_EQ(ls.size(), 2u);
  EXPECT_EQ(r.config->server.max_clients, 9u);
  const auto& plc = ls[0];
  EXPECT_EQ(plc.host, "0.0.0.0");
  EXPECT_EQ(plc.port, 502);
  EXPECT_EQ(ls[0].line, 5);
  EXPECT_FALSE(ls[0].from_server_listen);
  ASSERT_EQ(plc.policy.allow.size(), 3u);
  EXPECT_EQ(plc.policy.allow[0].to_string(), "10.1.2.0/24");
  EXPECT_EQ(plc.policy.allow[2].to_string(), "fd00::/8");
  EXPECT_EQ(plc.policy.access, AccessLevel::operate);
  EXPECT_EQ(plc.policy.word_order, WordOrder::little);
  EXPECT_FALSE(plc.policy.tls);
  const auto& secure = ls[1];
  EXPECT_EQ(secure.host, "::");
  EXPECT_EQ(secure.port, 802);
  EXPECT_EQ(secure.policy.access, AccessLevel::read);  // the default
  ASSERT_TRUE(secure.policy.tls);
  EXPECT_EQ(secure.policy.tls->key, "/etc/drivegate/tls/server.key");
  EXPECT_EQ(secure.policy.tls->roles.at("engineer"), AccessLevel::maintain);
  EXPECT_EQ(secure.policy.tls->roles.size(), 3u);
  // The plant listener has an allow list: no warning. The TLS one lets any address with a
  // certificate and a writing role write: said once.
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_THAT(r.warnings[0], AllOf(HasSubstr("gw.toml:11: listener: [::]:802 (TLS) lets every "
                                             "address with a certificate from its CA")));
}

TEST_F(ListenerConfig, AListenerThatSaysNothingElseIsReadOnlyAndUnwarned) {
  const auto r = parse("[[listener]]\naddress = \"127.0.0.1:1502\"\n");
  ASSERT_TRUE(r.config);
  EXPECT_EQ(r.config->listeners[0].policy.access, AccessLevel::read);
  EXPECT_TRUE(r.config->listeners[0].policy.allow.empty());
  EXPECT_THAT(r.warnings, IsEmpty());
}

TEST_F(ListenerConfig, ServerListenAndNothingAtAllKeepTheirOldMeaningWithAWarning) {
  for (const std::string text : {"[server]\nlisten = \"127.0.0.1:1502\"\n", ""}) {
    const auto r = parse(text);
    ASSERT_TRUE(r.config);
    ASSERT_EQ(r.config->listeners.size(), 1u);
    const auto& l = r.config->listeners[0];
    EXPECT_TRUE(l.from_server_listen);
    EXPECT_EQ(l.policy.access, AccessLevel::maintain);
    EXPECT_EQ(l.port, text.empty() ? 502 : 1502);
    ASSERT_EQ(r.warnings.size(), 1u);
    EXPECT_THAT(r.warnings[0], HasSubstr("lets every address that can reach it write (access "
                                         "maintain)"));
  }
}

TEST_F(ListenerConfig, MistakesAreNamedWithTheirLine) {
  EXPECT_THAT(
      errors("[server]\nlisten = \"0.0.0.0:502\"\n[[listener]]\naddress = \":503\"\n"),
      ElementsAre(AllOf(HasSubstr("gw.toml:3: listener:"), HasSubstr("cannot both be given"))));
  EXPECT_THAT(
      errors("[[listener]]\naddress = \"10.0.0.1\"\n"),
      ElementsAre(AllOf(HasSubstr("gw.toml:2: listener[0].address:"), HasSubstr("host:port"))));
  EXPECT_THAT(errors("[[listener]]\naccess = \"read\"\n"),
              ElementsAre(AllOf(HasSubstr("listener[0].address"), HasSubstr("missing"))));
  EXPECT_THAT(errors("[[listener]]\naddress = \":502\"\naccess = \"write\"\n"),
              ElementsAre(AllOf(HasSubstr("gw.toml:3: listener[0].access:"),
                                HasSubstr("\"read\", \"operate\" or \"maintain\""))));
  EXPECT_THAT(errors("[[listener]]\naddress = \":502\"\nword_order = \"middle\"\n"),
              ElementsAre(AllOf(HasSubstr("word_order"), HasSubstr("\"big\" or \"little\""))));
  EXPECT_THAT(errors("[[listener]]\naddress = \":502\"\nallow = [\"10.1.2.5/24\"]\n"),
              ElementsAre(AllOf(HasSubstr("gw.toml:3: listener[0].allow:"),
                                HasSubstr("bits set beyond /24"))));
  EXPECT_THAT(errors("[[listener]]\naddress = \":502\"\nallow = []\n"),
              ElementsAre(HasSubstr("nobody could connect")));
  EXPECT_THAT(errors("[[listener]]\naddress = \":502\"\nroles = { a = \"read\" }\n"),
              ElementsAre(AllOf(HasSubstr("roles"), HasSubstr("add tls"))));
  EXPECT_THAT(errors("[[listener]]\naddress = \":802\"\ntls = { cert = \"c\", key = \"k\" }\n"),
              ElementsAre(AllOf(HasSubstr("listener[0].tls.ca"), HasSubstr("missing"))));
  EXPECT_THAT(errors("[[listener]]\naddress = \":802\"\ntls = { cert = \"c\", key = \"k\", "
                     "ca = \"a\" }\nroles = { op = \"operator\" }\n"),
              ElementsAre(HasSubstr("listener[0].roles.op")));
  EXPECT_THAT(errors("[[listener]]\naddress = \"127.0.0.1:502\"\n"
                     "[[listener]]\naddress = \"127.0.0.1:502\"\naccess = \"read\"\n"),
              ElementsAre(AllOf(HasSubstr("gw.toml:3"), HasSubstr("already the address"),
                                HasSubstr("line 1"))));
  // [::] is dual stack: it takes 0.0.0.0's port too.
  EXPECT_THAT(errors("[[listener]]\naddress = \"0.0.0.0:502\"\n"
                     "[[listener]]\naddress = \"[::]:502\"\naccess = \"read\"\n"),
              ElementsAre(HasSubstr("overlaps 0.0.0.0:502")));
  EXPECT_THAT(errors("[[listener]]\naddress = \"plc.example:502\"\n"),
              ElementsAre(AllOf(HasSubstr("listener[0].address"),
                                HasSubstr("not a numeric IPv4 or IPv6 address"))));
  EXPECT_THAT(errors("[[listener]]\naddress = \":502\"\nport = \"/dev/ttyS1\"\nbaud = 9600\n"),
              ElementsAre(AllOf(HasSubstr("listener[0].address"),
                                HasSubstr("give address (a TCP listener) or port (a serial one), "
                                          "not both"))));
  EXPECT_THAT(errors("[[listener]]\naddress = \":502\"\nbaudrate = 5\n"),
              ElementsAre(AllOf(HasSubstr("listener[0].baudrate"), HasSubstr("unknown key"))));
}

// Each listener's own slots, and the TLS handshake rate; the defaults, the bounds and
// a handshake rate on a plain listener named with their line.
TEST_F(ListenerConfig, SlotsAndTheHandshakeRateArePerListener) {
  const auto r = parse(R"([server]
max_clients = 12
[[listener]]
address = "127.0.0.1:1502"
max_clients = 3
[[listener]]
address = "127.0.0.1:1802"
tls = { cert = "c", key = "k", ca = "a" }
tls_handshakes_per_s = 7
[[listener]]
address = "127.0.0.1:1803"
tls = { cert = "c", key = "k", ca = "a" }
)");
  ASSERT_TRUE(r.config) << ::testing::PrintToString(r.errors);
  const auto& ls = r.config->listeners;
  EXPECT_EQ(ls[0].policy.max_clients, std::optional<std::size_t>(3));
  EXPECT_EQ(ls[1].policy.max_clients, std::nullopt);  // [server] max_clients, 12
  EXPECT_EQ(ls[1].policy.handshakes, (net::RateLimit{7, 14}));
  EXPECT_EQ(ls[2].policy.handshakes, (net::RateLimit{5, 10}));  // the default
  EXPECT_THAT(
      errors("[[listener]]\naddress = \":502\"\nmax_clients = 0\n"),
      ElementsAre(AllOf(HasSubstr("gw.toml:3: listener[0].max_clients"), HasSubstr("1..1024"))));
  EXPECT_THAT(errors("[[listener]]\naddress = \":502\"\ntls_handshakes_per_s = 5\n"),
              ElementsAre(AllOf(HasSubstr("gw.toml:3: listener[0].tls_handshakes_per_s"),
                                HasSubstr("only a TLS listener"))));
  EXPECT_THAT(errors("[[listener]]\naddress = \":802\"\ntls = { cert = \"c\", key = \"k\", "
                     "ca = \"a\" }\ntls_handshakes_per_s = 1001\n"),
              ElementsAre(HasSubstr("listener[0].tls_handshakes_per_s")));
}

TEST_F(ListenerConfig, HttpIsOffUnlessAskedForAndItsKeysAreRead) {
  auto r = parse("[[listener]]\naddress = \"127.0.0.1:1502\"\n");
  ASSERT_TRUE(r.config);
  EXPECT_FALSE(r.config->http.enabled);
  r = parse(
      "[[listener]]\naddress = \"127.0.0.1:1502\"\n[http]\nlisten = \"127.0.0.1:8502\"\n"
      "allow = [\"127.0.0.1\"]\ncapture = true\n");
  ASSERT_TRUE(r.config) << ::testing::PrintToString(r.errors);
  EXPECT_TRUE(r.config->http.enabled);
  EXPECT_EQ(r.config->http.listen.port, 8502);
  EXPECT_EQ(r.config->http.allow.size(), 1u);
  EXPECT_TRUE(r.config->http.capture);
  EXPECT_EQ(r.config->http.requests_per_s, 20u);  // the default
  EXPECT_THAT(r.warnings, IsEmpty());
  r = parse("[[listener]]\naddress = \"127.0.0.1:1502\"\n[http]\nrequests_per_s = 0\n");
  ASSERT_TRUE(r.config) << ::testing::PrintToString(r.errors);
  EXPECT_EQ(r.config->http.requests_per_s, 0u);  // no limit
  EXPECT_THAT(
      errors("[[listener]]\naddress = \"127.0.0.1:1502\"\n[http]\nrequests_per_s = -1\n"),
      ElementsAre(AllOf(HasSubstr("gw.toml:4: http.requests_per_s"), HasSubstr("0..1000"))));
  // Reachable from anywhere, capture on: said.
  r = parse(
      "[[listener]]\naddress = \"127.0.0.1:1502\"\n[http]\nlisten = \"0.0.0.0:8502\"\n"
      "capture = true\n");
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_THAT(r.warnings[0],
              AllOf(HasSubstr("gw.toml:3: http:"), HasSubstr("capture the buses' traffic")));
  EXPECT_THAT(errors("[[listener]]\naddress = \"0.0.0.0:8502\"\naccess = \"read\"\n"
                     "[http]\nlisten = \"127.0.0.1:8502\"\n"),
              ElementsAre(HasSubstr("overlaps the Modbus listener on line 1")));
  EXPECT_THAT(errors("[[listener]]\naddress = \":1502\"\naccess = \"read\"\n"
                     "[http]\nlisten = \"status.local:8502\"\n"),
              ElementsAre(HasSubstr("numeric address")));
  EXPECT_THAT(errors("[[listener]]\naddress = \":1502\"\naccess = \"read\"\n"
                     "[http]\nport = 8502\n"),
              ElementsAre(AllOf(HasSubstr("http.port"), HasSubstr("unknown key"))));
}

}  // namespace
}  // namespace drivegate

namespace drivegate {
namespace {

// Serial listeners and RTU / ASCII over TCP (docs/serial-listeners.md).
TEST_F(ListenerConfig, ASerialListenerTakesALinesKeysWithTheSerialLinesDefaults) {
  const auto r = parse(R"(
[[listener]]
address = "0.0.0.0:502"
allow = ["10.1.2.0/24"]
access = "operate"

[[listener]]
port = "/dev/ttyS1"
baud = 19200
rs485 = true
access = "operate"
write_reply = "accepted"
reply_timeout_ms = 1500

[[listener]]
port = "/dev/ttyS2"
baud = 9600
framing = "ascii"
ascii_timeout_ms = 500
broadcast = true

[[listener]]
address = "127.0.0.1:4001"
framing = "rtu"
allow = ["127.0.0.1"]
reply_timeout_ms = 20
)");
  ASSERT_TRUE(r.config) << ::testing::PrintToString(r.errors);
  const auto& ls = r.config->listeners;
  ASSERT_EQ(ls.size(), 4U);
  EXPECT_FALSE(ls[0].serial);
  EXPECT_EQ(ls[0].framing, ListenerFraming::mbap);
  ASSERT_TRUE(ls[1].serial);
  EXPECT_EQ(ls[1].serial->port, "/dev/ttyS1");
  EXPECT_EQ(ls[1].serial->baud, 19200U);
  EXPECT_EQ(ls[1].serial->parity, Parity::even);  // Serial Line 2.5.1's default
  EXPECT_EQ(ls[1].serial->data_bits, 8);
  EXPECT_TRUE(ls[1].serial->rs485);
  EXPECT_EQ(ls[1].framing, ListenerFraming::rtu);
  EXPECT_EQ(ls[1].write_reply, WriteReply::accepted);
  EXPECT_EQ(ls[1].reply_timeout, Millis(1500));
  EXPECT_FALSE(ls[1].broadcast);
  EXPECT_EQ(ls[1].policy.access, AccessLevel::operate);
  ASSERT_TRUE(ls[2].serial);
  EXPECT_EQ(ls[2].framing, ListenerFraming::ascii);
  EXPECT_EQ(ls[2].serial->data_bits, 7);  // Serial Line 2.5.2's default for ASCII
  EXPECT_EQ(ls[2].ascii_timeout, Millis(500));
  EXPECT_TRUE(ls[2].broadcast);
  EXPECT_EQ(ls[2].policy.access, AccessLevel::read);
  EXPECT_EQ(ls[2].write_reply, WriteReply::confirmed);
  EXPECT_EQ(ls[2].reply_timeout, Millis(0));  // none: a reply waits for its drive
  EXPECT_FALSE(ls[3].serial);
  EXPECT_EQ(ls[3].framing, ListenerFraming::rtu);
  EXPECT_EQ(ls[3].port, 4001);
  EXPECT_EQ(ls[3].reply_timeout, Millis(20));  // RTU over TCP: a master's timeout as on a line
  // A serial listener lets no network address write: no warning about it.
  EXPECT_THAT(r.warnings, IsEmpty());
}

TEST_F(ListenerConfig, SerialListenerMistakesAreNamedWithTheirLine) {
  EXPECT_THAT(errors("[[listener]]\nport = \"/dev/ttyS1\"\n"),
              ElementsAre(AllOf(HasSubstr("gw.toml:2: listener[0].baud"),
                                HasSubstr("needs its line's baud rate"))));
  EXPECT_THAT(errors("[[listener]]\nport = \"rfc2217://10.0.0.5:4001\"\n"),
              ElementsAre(HasSubstr("needs its line's baud rate")));
  EXPECT_THAT(
      errors("[[listener]]\naddress = \":502\"\nbaud = 9600\n"),
      ElementsAre(AllOf(HasSubstr("listener[0].baud"), HasSubstr("only for a serial listener"))));
  EXPECT_THAT(errors("[[listener]]\naddress = \":4001\"\nframing = \"rtu\"\nrx_latency_ms = 5\n"),
              ElementsAre(HasSubstr("only for framing = \"rtu\" on a serial port")));
  EXPECT_THAT(
      errors("[[listener]]\naddress = \":4001\"\nframing = \"ascii\"\nascii_timeout_ms = 50\n"),
      ElementsAre(HasSubstr("on a serial port")));
  EXPECT_THAT(errors("[[listener]]\nport = \"/dev/ttyS1\"\nbaud = 9600\nframing = \"mbap\"\n"),
              ElementsAre(HasSubstr("a serial line carries \"rtu\" or \"ascii\" frames")));
  EXPECT_THAT(errors("[[listener]]\nport = \"/dev/ttyS1\"\nbaud = 9600\ndata_bits = 7\n"),
              ElementsAre(HasSubstr("RTU frames are 8 data bits")));
  EXPECT_THAT(errors("[[listener]]\nport = \"/dev/ttyS1\"\nbaud = 9600\nallow = [\"10.0.0.1\"]\n"),
              ElementsAre(AllOf(HasSubstr("listener[0].allow"), HasSubstr("no network clients"))));
  EXPECT_THAT(errors("[[listener]]\nport = \"/dev/ttyS1\"\nbaud = 9600\nascii_timeout_ms = 50\n"),
              ElementsAre(HasSubstr("only for framing = \"ascii\"")));
  EXPECT_THAT(errors("[[listener]]\naddress = \":502\"\nwrite_reply = \"accepted\"\n"),
              ElementsAre(AllOf(HasSubstr("listener[0].write_reply"),
                                HasSubstr("only for a listener with framing"))));
  EXPECT_THAT(errors("[[listener]]\naddress = \":502\"\nframing = \"rtu\"\ntls = { cert = "
                     "\"/c\", key = \"/k\", ca = \"/a\" }\n"),
              ::testing::Contains(HasSubstr("a TLS listener's framing is \"mbap\"")));
  EXPECT_THAT(errors("[[listener]]\naddress = \":502\"\nreply_timeout_ms = 1000\n"),
              ElementsAre(AllOf(HasSubstr("listener[0].reply_timeout_ms"),
                                HasSubstr("only for a listener with framing"))));
  EXPECT_THAT(errors("[[listener]]\nport = \"/dev/ttyS1\"\nbaud = 9600\nreply_timeout_ms = -1\n"),
              ElementsAre(HasSubstr("listener[0].reply_timeout_ms")));
  EXPECT_THAT(
      errors("[[listener]]\nport = \"/dev/ttyS1\"\nbaud = 9600\nreply_timeout_ms = 60001\n"),
      ElementsAre(HasSubstr("listener[0].reply_timeout_ms")));
  EXPECT_THAT(errors("[[listener]]\nport = \"/dev/ttyS1\"\nbaud = 9600\nreply_timeout_ms = 5\n"),
              ElementsAre(AllOf(HasSubstr("gw.toml:4: listener[0].reply_timeout_ms"),
                                HasSubstr("0 (none) or at least 20 ms"))));
  EXPECT_THAT(errors("[[listener]]\nport = \"/dev/ttyS1\"\nbaud = 9600\nwrite_reply = \"later\"\n"),
              ElementsAre(HasSubstr("must be \"confirmed\" or \"accepted\"")));
  // The drives' line is not a master's: the bus in kDevice is on /dev/ttyUSB0.
  EXPECT_THAT(errors("[[listener]]\nport = \"/dev/ttyUSB0\"\nbaud = 9600\n"),
              ElementsAre(AllOf(HasSubstr("gw.toml:1: listener"), HasSubstr("is bus 'line1''s"))));
  // The same port by another name: a symbolic link to it (as /dev/serial/by-id/... are).
  const auto dir =
      std::filesystem::temp_directory_path() / ("drivegate-ports-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "ttyUSB7") << "";
  std::filesystem::create_symlink(dir / "ttyUSB7", dir / "by-id-adapter");
  const auto r = parse_config("[[listener]]\nport = \"" + (dir / "by-id-adapter").string() +
                                  "\"\nbaud = 9600\n\n[[bus]]\nname = \"drives\"\nport = \"" +
                                  (dir / "ttyUSB7").string() + "\"\n" + std::string(kDevice),
                              "gw.toml", plugins_);
  std::filesystem::remove_all(dir);
  EXPECT_THAT(r.errors, Contains(HasSubstr("is bus 'drives''s")));
  EXPECT_THAT(errors("[[listener]]\nport = \"/dev/ttyS1\"\nbaud = 9600\n\n[[listener]]\nport = "
                     "\"/dev/ttyS1\"\nbaud = 19200\n"),
              ElementsAre(HasSubstr("is already the listener's on line 1")));
}

}  // namespace
}  // namespace drivegate
