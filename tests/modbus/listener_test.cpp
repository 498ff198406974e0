// Listeners: allow lists closing clients at accept, access levels and word order reaching the
// backend with every request, denied writes counted, policies changed on a running server, and
// Modbus/TCP Security (TLS with client certificates made by tests/support/make_certs.sh, the
// role read from the certificate).
#include <gtest/gtest.h>
#include <openssl/pem.h>
#include <sys/stat.h>

#include <boost/asio/connect.hpp>
#include <boost/asio/read.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/asio/write.hpp>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "harness.h"
#include "net/acceptor.h"
#include "tls.h"

namespace drivegate::modbus {
namespace {

using test::Bytes;
using test::Harness;
using test::RawClient;
using test::request;
using test::operator+;
namespace asio = boost::asio;

net::AddressRange range(std::string_view text) {
  std::string error;
  return net::parse_address_range(text, error).value();
}

ServerOptions with(std::vector<ListenerPolicy> policies) {
  ServerOptions o;
  o.listeners.clear();
  for (auto& p : policies) {
    ListenerOptions l;
    l.policy = std::move(p);
    o.listeners.push_back(std::move(l));
  }
  return o;
}

const Bytes kWriteSetpoint = request(1, 1, {0x06, 0x00, 0x01, 0x04, 0xB0});
const Bytes kReadHolding = request(2, 1, {0x03, 0x00, 0x01, 0x00, 0x01});

TEST(Listener, AClientOutsideTheAllowListIsClosedBeforeItsRequestIsRead) {
  Harness h(with({{.allow = {range("192.0.2.1")}}, {}}));
  ASSERT_FALSE(h.listen_error());
  RawClient outsider(h.port(0));
  ASSERT_TRUE(outsider.connected());  // TCP accepts; the server closes at once
  outsider.send(kWriteSetpoint);
  EXPECT_TRUE(outsider.closed_by_peer());
  EXPECT_EQ(h.stats().connections_not_allowed, 1u);
  EXPECT_EQ(h.stats().connections_accepted, 0u);
  EXPECT_EQ(h.with_backend([](test::FakeBackend& b) { return b.writes.size() + b.reads; }), 0u);
  // The other listener of the same server serves loopback as usual.
  RawClient insider(h.port(1));
  insider.send(kReadHolding);
  EXPECT_EQ(insider.reply().size(), 11u);
}

TEST(Listener, AReadListenerAnswersWritesWithException01AndCountsThem) {
  Harness h(with({{.access = AccessLevel::read}}));
  RawClient c(h.port());
  for (std::uint16_t t = 1; t <= 3; ++t) {
    c.send(request(t, 1, {0x06, 0x00, 0x01, 0x04, 0xB0}));
    EXPECT_EQ(c.reply(), request(t, 1, {0x86, 0x01}));
  }
  c.send(kReadHolding);
  EXPECT_EQ(c.reply().size(), 11u);  // reads are served
  EXPECT_EQ(h.stats().writes_denied, 3u);
  EXPECT_EQ(h.stats().exceptions[1], 3u);
  EXPECT_TRUE(h.with_backend([](test::FakeBackend& b) { return b.writes.empty(); }));
}

TEST(Listener, EachListenersAccessAndWordOrderTravelWithItsRequests) {
  Harness h(with({{.access = AccessLevel::operate, .word_order = WordOrder::little},
                  {.access = AccessLevel::maintain}}));
  RawClient little(h.port(0));
  RawClient big(h.port(1));
  little.send(kReadHolding);
  little.reply();
  auto s = h.with_backend([](test::FakeBackend& b) { return b.last_session; });
  EXPECT_EQ(s.access, AccessLevel::operate);
  EXPECT_EQ(s.word_order, WordOrder::little);
  big.send(kWriteSetpoint);
  big.reply();
  s = h.with_backend([](test::FakeBackend& b) { return b.last_session; });
  EXPECT_EQ(s.access, AccessLevel::maintain);
  EXPECT_EQ(s.word_order, WordOrder::big);
}

TEST(Listener, AReloadChangesTheAccessOfOpenConnectionsAndClosesThoseNoLongerAllowed) {
  Harness h(with({{.access = AccessLevel::maintain}}));
  RawClient c(h.port());
  c.send(kWriteSetpoint);
  EXPECT_EQ(c.reply(), kWriteSetpoint);
  // Same address (the harness bound 127.0.0.1:0, so the running listener is 127.0.0.1:0).
  ListenerOptions read_only;
  read_only.host = "127.0.0.1";
  read_only.port = 0;
  read_only.policy.access = AccessLevel::read;
  const auto r = h.on_io([&] { return h.server().reload_listeners({read_only}); });
  EXPECT_TRUE(r.errors.empty());
  EXPECT_TRUE(r.restart_needed.empty());
  c.send(kWriteSetpoint);
  EXPECT_EQ(c.reply(), request(1, 1, {0x86, 0x01}));

  ListenerOptions elsewhere = read_only;
  elsewhere.policy.allow = {range("192.0.2.0/24")};
  h.on_io([&] { return h.server().reload_listeners({elsewhere}); });
  EXPECT_TRUE(c.closed_by_peer());
  EXPECT_TRUE(h.wait_clients(0));
}

TEST(Listener, AReloadCannotAddOrMoveAListenerWithoutARestart) {
  Harness h(with({{}}));
  ListenerOptions moved;
  moved.host = "127.0.0.1";
  moved.port = 1;  // not the running one
  const auto r = h.on_io([&] { return h.server().reload_listeners({moved}); });
  EXPECT_TRUE(r.errors.empty());
  ASSERT_EQ(r.restart_needed.size(), 2u);  // the new one, and the running one it would replace
  EXPECT_EQ(r.restart_needed[0], "127.0.0.1:1");
  RawClient c(h.port());  // still serving where it was
  c.send(kReadHolding);
  EXPECT_EQ(c.reply().size(), 11u);
}

// --- Modbus/TCP Security ------------------------------------------------------------------

class Tls : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = std::filesystem::temp_directory_path() /
           ("drivegate-tls-test-" + std::to_string(::getpid()));
    const std::string cmd = std::string(DRIVEGATE_SOURCE_DIR) + "/tests/support/make_certs.sh " +
                            dir_.string() + " >/dev/null 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }
  static std::string file(const std::string& name) { return (dir_ / name).string(); }

  static TlsOptions server_files() {
    TlsOptions t;
    t.cert = dir_ / "server.pem";
    t.key = dir_ / "server.key";
    t.ca = dir_ / "ca.pem";
    t.roles = {{"viewer", AccessLevel::read}, {"operator", AccessLevel::operate}};
    return t;
  }

  // A blocking TLS client with `name`.pem / .key; the reply to `req`, or empty when the
  // handshake or the exchange failed.
  static Bytes exchange(std::uint16_t port, const std::string& name, const Bytes& req) {
    asio::io_context io;
    asio::ssl::context ctx(asio::ssl::context::tls_client);
    boost::system::error_code ec;
    ctx.load_verify_file(file("ca.pem"), ec);
    ctx.use_certificate_chain_file(file(name + ".pem"), ec);
    ctx.use_private_key_file(file(name + ".key"), asio::ssl::context::pem, ec);
    ctx.set_verify_mode(asio::ssl::verify_peer);
    asio::ssl::stream<asio::ip::tcp::socket> s(io, ctx);
    s.next_layer().connect({asio::ip::make_address("127.0.0.1"), port}, ec);
    if (ec) return {};
    s.handshake(asio::ssl::stream_base::client, ec);
    if (ec) return {};
    asio::write(s, asio::buffer(req), ec);
    Bytes head(7);
    asio::read(s, asio::buffer(head), ec);
    if (ec) return {};
    Bytes rest(((head[4] << 8) | head[5]) - 1u);
    asio::read(s, asio::buffer(rest), ec);
    if (ec) return {};
    return head + rest;
  }

  static inline std::filesystem::path dir_;
};

TEST_F(Tls, TheRoleInTheClientCertificateSetsTheAccessLevel) {
  Harness h(with({{.access = AccessLevel::read, .tls = server_files()}}));
  ASSERT_FALSE(h.listen_error());
  EXPECT_EQ(exchange(h.port(), "operator", kWriteSetpoint), kWriteSetpoint);
  EXPECT_EQ(h.with_backend([](test::FakeBackend& b) { return b.last_session.access; }),
            AccessLevel::operate);
  // A viewer, an unknown role (engineer is not in this listener's roles) and no role at all get
  // the listener's access: read.
  for (const char* who : {"viewer", "engineer", "norole"}) {
    EXPECT_EQ(exchange(h.port(), who, kWriteSetpoint), request(1, 1, {0x86, 0x01})) << who;
    EXPECT_EQ(exchange(h.port(), who, kReadHolding).size(), 11u) << who;
  }
  EXPECT_EQ(h.stats().writes_denied, 3u);
  EXPECT_EQ(h.with_backend([](test::FakeBackend& b) { return b.writes.size(); }), 1u);
}

TEST_F(Tls, CertificatesFromAnotherCaOrExpiredAreRefusedInTheHandshake) {
  Harness h(with({{.tls = server_files()}}));
  EXPECT_TRUE(exchange(h.port(), "otherca", kReadHolding).empty());
  EXPECT_TRUE(exchange(h.port(), "expired", kReadHolding).empty());
  // The client can see the server's alert before the server's handshake handler has run.
  h.eventually([&h] { return h.server().stats().tls_handshake_failures >= 2; });
  EXPECT_EQ(h.stats().tls_handshake_failures, 2u);
  EXPECT_EQ(exchange(h.port(), "operator", kReadHolding).size(), 11u);  // others unaffected
  EXPECT_EQ(h.with_backend([](test::FakeBackend& b) { return b.reads; }), 1u);
}

// Issue 24: a handshake flood from one address is closed at accept, before the server signs
// anything; a plaintext listener beside it, and the same address a moment later, are served.
TEST_F(Tls, AHandshakeFloodFromOneAddressIsClosedAtAccept) {
  Harness h(with({{.tls = server_files(), .handshakes = {1, 3}}, {}}));
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(exchange(h.port(0), "operator", kReadHolding).size(), 11u) << i;
  }
  for (int i = 0; i < 20; ++i) {
    EXPECT_TRUE(exchange(h.port(0), "operator", kReadHolding).empty());
    h.advance(net::kHoldOff);  // the listener takes its next client that much later
  }
  const auto s = h.stats();
  EXPECT_EQ(s.tls_handshakes_limited, 20u);  // 100 ms of the server's time: no token back
  EXPECT_EQ(s.tls_handshake_failures, 0u);   // closed at accept, never handshaken
  EXPECT_EQ(h.on_io([&] { return h.server().listener_stats(0).tls_handshakes_limited; }),
            s.tls_handshakes_limited);
  RawClient plain(h.port(1));
  plain.send(kReadHolding);
  EXPECT_EQ(plain.reply().size(), 11u);
  h.advance(std::chrono::milliseconds(900));  // a second after the flood began: a token again
  EXPECT_EQ(exchange(h.port(0), "operator", kReadHolding).size(), 11u);
}

TEST_F(Tls, PlainModbusOnATlsListenerIsNeverRead) {
  Harness h(with({{.tls = server_files()}}));
  RawClient c(h.port());
  c.send(kReadHolding);
  EXPECT_TRUE(c.closed_by_peer());  // no Modbus reply: the "ClientHello" was not TLS
  EXPECT_EQ(h.stats().tls_handshake_failures, 1u);
  EXPECT_EQ(h.with_backend([](test::FakeBackend& b) { return b.reads; }), 0u);
}

TEST_F(Tls, AClientThatNeverFinishesTheHandshakeIsClosedAfterFrameTimeout) {
  auto o = with({{.tls = server_files()}});
  o.frame_timeout = std::chrono::milliseconds(200);
  Harness h(o);
  RawClient c(h.port());
  EXPECT_TRUE(h.wait_clients(1));
  h.advance(std::chrono::milliseconds(199));
  EXPECT_FALSE(c.closed_by_peer(std::chrono::milliseconds(100)));
  h.advance(std::chrono::milliseconds(1));
  EXPECT_TRUE(c.closed_by_peer(std::chrono::milliseconds(3000)));
  EXPECT_EQ(h.stats().tls_handshake_failures, 1u);
}

TEST_F(Tls, AKeyOthersMayReadIsRefusedNamingTheFile) {
  const auto key = dir_ / "shared.key";
  std::filesystem::copy_file(dir_ / "server.key", key,
                             std::filesystem::copy_options::overwrite_existing);
  ::chmod(key.c_str(), 0644);
  auto files = server_files();
  files.key = key;
  std::string error;
  EXPECT_FALSE(make_tls_context(files, error));
  EXPECT_NE(error.find(key.string() + " is readable by others (mode 0644)"), std::string::npos)
      << error;
  Harness h(with({{.tls = files}}));
  EXPECT_TRUE(h.listen_error());
  ::chmod(key.c_str(), 0640);  // a group the service is in may read it
  EXPECT_TRUE(make_tls_context(files, error)) << error;
}

TEST_F(Tls, MissingOrMismatchedFilesAreNamed) {
  auto files = server_files();
  files.cert = dir_ / "nope.pem";
  std::string error;
  EXPECT_FALSE(make_tls_context(files, error));
  EXPECT_NE(error.find("nope.pem"), std::string::npos) << error;
  files = server_files();
  files.cert = dir_ / "operator.pem";  // another key's certificate
  EXPECT_FALSE(make_tls_context(files, error));
  // OpenSSL notices while loading the key: "cannot load key .../server.key: key values mismatch".
  EXPECT_NE(error.find("server.key"), std::string::npos) << error;
  EXPECT_NE(error.find("mismatch"), std::string::npos) << error;
}

// Issue 24: a TLS file that is a FIFO would block OpenSSL's read forever (at start-up, or at
// SIGHUP on the event loop): refused at once, saying what it is.
TEST_F(Tls, AFileThatIsNotARegularFileIsRefusedWithoutWaiting) {
  auto files = server_files();
  const auto fifo = dir_ / "ca.fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  files.ca = fifo;
  std::string error;
  const auto asked = std::chrono::steady_clock::now();
  EXPECT_FALSE(make_tls_context(files, error));
  EXPECT_LT(std::chrono::steady_clock::now() - asked, std::chrono::seconds(2));
  EXPECT_NE(error.find("ca.fifo: a FIFO, not a regular file"), std::string::npos) << error;
  files = server_files();
  files.cert = "/dev/zero";
  EXPECT_FALSE(make_tls_context(files, error));
  EXPECT_NE(error.find("/dev/zero: a character device"), std::string::npos) << error;
}

TEST_F(Tls, TheRoleIsTheUtf8StringOfTheModbusSecurityExtension) {
  const auto role_of = [](const std::string& name) {
    std::FILE* f = std::fopen(file(name + ".pem").c_str(), "r");
    X509* cert = PEM_read_X509(f, nullptr, nullptr, nullptr);
    std::fclose(f);
    auto role = certificate_role(cert);
    X509_free(cert);
    return role;
  };
  EXPECT_EQ(role_of("operator"), "operator");
  EXPECT_EQ(role_of("engineer"), "engineer");
  EXPECT_EQ(role_of("norole"), std::nullopt);
  EXPECT_EQ(role_of("server"), std::nullopt);
}

}  // namespace
}  // namespace drivegate::modbus
