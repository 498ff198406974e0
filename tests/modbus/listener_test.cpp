// Listeners: allow lists closing clients at accept, access levels and word order reaching the
// backend with every request, denied writes counted, policies changed on a running server, and
// Modbus/TCP Security (TLS with client certificates made by tests/support/make_certs.sh, the
// role read from the certificate).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <openssl/err.h>
#include <openssl/pem.h>
#include <openssl/ssl.h>
#include <poll.h>
#include <sys/stat.h>
#include <time.h>

#include <atomic>
#include <boost/asio/connect.hpp>
#include <boost/asio/read.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/asio/write.hpp>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "handshaker.h"
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
using namespace std::chrono_literals;

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

// What a client read of the drives' faults (gateway/fault_reads.h) is its connection's own: the
// same record with each of its requests, and another connection's is another.
TEST(Listener, EachConnectionKeepsItsOwnRecordOfTheFaultsItRead) {
  Harness h(with({{.access = AccessLevel::operate}}));
  RawClient first(h.port());
  RawClient second(h.port());
  const auto reads = [&] {
    return h.with_backend([](test::FakeBackend& b) { return b.last_session.fault_reads; });
  };
  first.send(kReadHolding);
  first.reply();
  const std::shared_ptr<FaultReads> of_first = reads();
  ASSERT_NE(of_first, nullptr);
  first.send(kWriteSetpoint);
  first.reply();
  EXPECT_EQ(reads(), of_first);
  second.send(kReadHolding);
  second.reply();
  ASSERT_NE(reads(), nullptr);
  EXPECT_NE(reads(), of_first);
}

// A read of the fault state counts for the client's runs once its reply went out and the client
// sent more after it: a read and a write sent in one segment (pipelined) were decided before the
// read's reply, and the write finds nothing seen; the next write, sent after the reply came,
// finds the fault the read showed.
TEST(Listener, AReadCountsForWhatTheClientSendsAfterItsReplyNotWithIt) {
  Harness h(with({{.access = AccessLevel::operate}}));
  RawClient c(h.port());
  const Bytes read_state = request(3, 1, {0x04, 0x00, 0x00, 0x00, 0x01});  // input 0: kFaultState
  Bytes pipelined = read_state;
  pipelined.insert(pipelined.end(), kWriteSetpoint.begin(), kWriteSetpoint.end());
  ASSERT_TRUE(c.send(pipelined));
  EXPECT_EQ(c.reply().size(), 11u);
  EXPECT_EQ(c.reply(), kWriteSetpoint);
  const auto seen = [&] {
    return h.with_backend([](test::FakeBackend& b) { return b.writes_fault_seen; });
  };
  ASSERT_EQ(seen().size(), 1u);
  EXPECT_FALSE(seen().back()) << "sent with the read, before its reply";
  ASSERT_TRUE(c.send(kWriteSetpoint));
  EXPECT_EQ(c.reply(), kWriteSetpoint);
  ASSERT_EQ(seen().size(), 2u);
  EXPECT_TRUE(seen().back()) << "sent after the read's reply";
}

// A write whose first bytes came with a read (its rest after the read's reply) was begun before
// that reply: it finds nothing seen.
TEST(Listener, AWriteBegunBeforeTheReadsReplyDoesNotCountIt) {
  Harness h(with({{.access = AccessLevel::operate}}));
  RawClient c(h.port());
  Bytes first = request(3, 1, {0x04, 0x00, 0x00, 0x00, 0x01});  // input 0: kFaultState
  first.insert(first.end(), kWriteSetpoint.begin(), kWriteSetpoint.begin() + 5);
  ASSERT_TRUE(c.send(first));
  EXPECT_EQ(c.reply().size(), 11u);
  ASSERT_TRUE(c.send(Bytes(kWriteSetpoint.begin() + 5, kWriteSetpoint.end())));
  EXPECT_EQ(c.reply(), kWriteSetpoint);
  const auto seen = h.with_backend([](test::FakeBackend& b) { return b.writes_fault_seen; });
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_FALSE(seen.back());
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
    // The stepped client writes with OpenSSL's socket BIO (write(2)): a server that closed is
    // an error there, not a signal.
    ::signal(SIGPIPE, SIG_IGN);
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

// A handshake flood from one address is closed at accept, before the server signs
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

// A TLS file that is a FIFO would block OpenSSL's read forever (at start-up, or at
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

// --- TLS handshakes on the server's handshake thread (handshaker.h) ------------------------

// This thread's CPU time.
std::chrono::nanoseconds thread_cpu() {
  timespec t{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return std::chrono::seconds(t.tv_sec) + std::chrono::nanoseconds(t.tv_nsec);
}

// Whether a thread of this process has the handshake thread's name.
bool handshake_thread_runs() {
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
    std::string name;
    std::getline(std::ifstream(task.path() / "comm"), name);
    if (name == kHandshakeThreadName) return true;
  }
  return false;
}

// The first bytes of a ClientHello: a TLS handshake record announcing 512 bytes, and 6 of them.
const Bytes kHalfClientHello = {0x16, 0x03, 0x01, 0x02, 0x00, 0x01, 0x00, 0x01, 0xFC, 0x03, 0x03};

// Whether the server closed `c`, having sent it nothing or a TLS alert, never a Modbus reply.
bool refused(RawClient& c) {
  const Bytes got = c.recv(64, 3000ms);
  return (got.empty() || got[0] == 0x15) && c.closed_by_peer(100ms);
}

// A TLS client driven a step at a time (non-blocking OpenSSL on its own socket): its ClientHello
// sent and the handshake left there, to be finished later.
class SteppedTlsClient {
 public:
  SteppedTlsClient(std::uint16_t port, const std::string& dir, const std::string& name)
      : tcp_(port), ctx_(SSL_CTX_new(TLS_client_method())) {
    SSL_CTX_use_certificate_chain_file(ctx_, (dir + "/" + name + ".pem").c_str());
    SSL_CTX_use_PrivateKey_file(ctx_, (dir + "/" + name + ".key").c_str(), SSL_FILETYPE_PEM);
    SSL_CTX_load_verify_locations(ctx_, (dir + "/ca.pem").c_str(), nullptr);
    SSL_CTX_set_verify(ctx_, SSL_VERIFY_PEER, nullptr);
    ssl_ = SSL_new(ctx_);
    ::fcntl(tcp_.fd(), F_SETFL, ::fcntl(tcp_.fd(), F_GETFL) | O_NONBLOCK);
    // Until finish(), OpenSSL reads from an empty memory BIO: the ClientHello goes out, and
    // whatever the server answers waits in the socket, however late this thread runs.
    BIO* nothing = BIO_new(BIO_s_mem());
    BIO_set_mem_eof_return(nothing, -1);
    SSL_set_bio(ssl_, nothing, BIO_new_socket(tcp_.fd(), BIO_NOCLOSE));
  }
  ~SteppedTlsClient() {
    SSL_free(ssl_);
    SSL_CTX_free(ctx_);
  }
  SteppedTlsClient(const SteppedTlsClient&) = delete;
  SteppedTlsClient& operator=(const SteppedTlsClient&) = delete;

  // Sends the ClientHello, and waits for the server's answer without reading it: the server
  // has done its first step and waits for the client's certificate.
  bool hello() {
    ERR_clear_error();  // SSL_get_error reads this thread's queue: an earlier test's errors
    const int r = SSL_connect(ssl_);
    return r < 0 && SSL_get_error(ssl_, r) == SSL_ERROR_WANT_READ && tcp_.readable(5000ms);
  }
  // The rest of the handshake.
  bool finish() {
    read_the_socket();
    return drive([this] { return SSL_connect(ssl_); }) > 0;
  }
  // One request and its reply (empty when the server closed).
  Bytes exchange(const Bytes& req) { return send(req) ? reply() : Bytes{}; }
  void abort() { tcp_.abort(); }
  // TCP half-close, without close_notify.
  void shutdown_write() { tcp_.shutdown_write(); }
  // Sends `req` without waiting for the reply.
  bool send(const Bytes& req) {
    return drive([&] { return SSL_write(ssl_, req.data(), static_cast<int>(req.size())); }) > 0;
  }
  // One reply (empty when the server closed first).
  Bytes reply() {
    Bytes out(7);
    if (!read_exactly(out.data(), 7)) return {};
    out.resize(7 + ((out[4] << 8) | out[5]) - 1);
    if (!read_exactly(out.data() + 7, out.size() - 7)) return {};
    return out;
  }

 private:
  void read_the_socket() {
    if (!reading_) SSL_set0_rbio(ssl_, BIO_new_socket(tcp_.fd(), BIO_NOCLOSE));
    reading_ = true;
  }
  bool read_exactly(std::uint8_t* into, std::size_t n) {
    for (std::size_t at = 0; at < n;) {
      const int r = drive([&] { return SSL_read(ssl_, into + at, static_cast<int>(n - at)); });
      if (r <= 0) return false;
      at += static_cast<std::size_t>(r);
    }
    return true;
  }
  // Repeats `op` while OpenSSL waits for the socket, up to 5 s.
  template <class Op>
  int drive(Op op) {
    const auto end = std::chrono::steady_clock::now() + 5s;
    for (;;) {
      ERR_clear_error();
      const int r = op();
      if (r > 0) return r;
      const int e = SSL_get_error(ssl_, r);
      if (e != SSL_ERROR_WANT_READ && e != SSL_ERROR_WANT_WRITE) return -1;
      if (std::chrono::steady_clock::now() > end) return -1;
      pollfd p{.fd = tcp_.fd(),
               .events = static_cast<short>(e == SSL_ERROR_WANT_READ ? POLLIN : POLLOUT),
               .revents = 0};
      ::poll(&p, 1, 100);
    }
  }

  RawClient tcp_;
  SSL_CTX* ctx_;
  SSL* ssl_ = nullptr;
  bool reading_ = false;  // from the socket (after hello)
};

// No address limit in these tests: they make many handshakes from 127.0.0.1.
ListenerPolicy tls_policy(TlsOptions files) {
  return {.tls = std::move(files), .handshakes = {0, 1}};
}

TEST_F(Tls, TheHandshakeRunsOnTheHandshakeThreadNotOnTheEventLoop) {
  {
    Harness h(with({tls_policy(server_files())}));
    ASSERT_FALSE(h.listen_error());
    EXPECT_TRUE(handshake_thread_runs());
    const auto loop_before = h.on_io([] { return thread_cpu(); });
    const auto client_before = thread_cpu();
    constexpr int kHandshakes = 20;
    for (int i = 0; i < kHandshakes; ++i) {
      ASSERT_EQ(exchange(h.port(), "operator", kReadHolding).size(), 11u) << i;
    }
    const auto client = thread_cpu() - client_before;
    const auto loop = h.on_io([] { return thread_cpu(); }) - loop_before;
    std::cerr << kHandshakes << " full handshakes: event loop " << loop.count() / 1000
              << " us of CPU, the client " << client.count() / 1000 << " us\n";
#if !defined(__SANITIZE_THREAD__)
    // The server's side of a handshake (an ECDHE, a signature, a certificate chain verified)
    // costs about what the client's does. The loop now only accepts, reads the role and serves
    // the one request: a small part of it. (ThreadSanitizer slows the loop's instrumented code
    // tenfold and OpenSSL's not at all: not a measure there.)
    EXPECT_LT(loop * 4, client);
#endif
  }
  EXPECT_FALSE(handshake_thread_runs());  // joined with the server
  Harness plain;
  EXPECT_FALSE(handshake_thread_runs());  // no TLS listener, no thread
}

TEST_F(Tls, AStalledHandshakeHoldsNeitherTheEventLoopNorOtherHandshakes) {
  auto o = with({tls_policy(server_files()), {}});
  o.frame_timeout = std::chrono::milliseconds(2000);
  Harness h(o);
  SteppedTlsClient stalled(h.port(0), dir_.string(), "operator");
  ASSERT_TRUE(stalled.hello());  // the handshake thread answered and waits for it
  RawClient silent(h.port(0));
  RawClient half(h.port(0));
  ASSERT_TRUE(half.send(kHalfClientHello));
  EXPECT_TRUE(h.wait_clients(3));
  // A plaintext client and another TLS client are served meanwhile.
  RawClient plain(h.port(1));
  plain.send(kReadHolding);
  EXPECT_EQ(plain.reply().size(), 11u);
  EXPECT_EQ(exchange(h.port(0), "operator", kReadHolding).size(), 11u);
  // The stalled one goes on where it stopped.
  ASSERT_TRUE(stalled.finish());
  EXPECT_EQ(stalled.exchange(kReadHolding).size(), 11u);
  EXPECT_EQ(h.stats().tls_handshake_failures, 0u);
  // The two that never finish are closed at the time limit, on the server's clock.
  h.advance(std::chrono::milliseconds(2000));
  EXPECT_TRUE(silent.closed_by_peer(3000ms));
  EXPECT_TRUE(half.closed_by_peer(3000ms));
  EXPECT_EQ(h.stats().tls_handshake_failures, 2u);
  plain.send(kReadHolding);
  EXPECT_EQ(plain.reply().size(), 11u);
  EXPECT_EQ(stalled.exchange(kReadHolding).size(), 11u);
  EXPECT_EQ(h.with_backend([](test::FakeBackend& b) { return b.reads; }), 5u);
}

TEST_F(Tls, GarbageOrAClientGoneMidHandshakeFailsAloneAndIsCounted) {
  Harness h(with({tls_policy(server_files())}));
  const std::vector<Bytes> garbage = {
      Bytes{'G', 'E', 'T', ' ', '/', ' ', 'H', 'T', 'T', 'P', '/', '1', '.', '1', '\r', '\n'},
      // A Modbus request inside a TLS handshake record.
      Bytes{0x16, 0x03, 0x01, 0x00, 0x0C} + kReadHolding,
      // A ClientHello with a length past its record, then a 64 KiB record.
      Bytes{0x16, 0x03, 0x01, 0x00, 0x08, 0x01, 0xFF, 0xFF, 0xFF, 0x03, 0x03, 0x00, 0x00},
      Bytes{0x16, 0x03, 0x03, 0xFF, 0xFF} + Bytes(300, 0xAA),
  };
  const auto failures = [&h](std::uint64_t n) {
    return h.eventually([&h, n] { return h.server().stats().tls_handshake_failures == n; });
  };
  for (const auto& g : garbage) {
    RawClient c(h.port());
    c.send(g);
    EXPECT_TRUE(refused(c));
  }
  EXPECT_TRUE(failures(4));
  {
    RawClient half(h.port());  // half a ClientHello, then gone (FIN)
    half.send(kHalfClientHello);
  }
  EXPECT_TRUE(failures(5));
  RawClient reset(h.port());  // half a ClientHello, then a reset
  reset.send(kHalfClientHello);
  EXPECT_TRUE(h.wait_clients(1));
  reset.abort();
  EXPECT_TRUE(failures(6));
  SteppedTlsClient gone(h.port(), dir_.string(), "operator");  // its server's flight unread
  ASSERT_TRUE(gone.hello());
  gone.abort();
  EXPECT_TRUE(failures(7)) << h.stats().tls_handshake_failures;
  EXPECT_TRUE(h.wait_clients(0));
  EXPECT_EQ(exchange(h.port(), "operator", kReadHolding).size(), 11u);
  EXPECT_EQ(h.with_backend([](test::FakeBackend& b) { return b.reads; }), 1u);
}

// A TLS client that shuts its side down, with or without close_notify, has said all it will: what
// it sent is answered, then the connection closes.
TEST_F(Tls, AClientThatHalfClosesIsStillAnswered) {
  Harness h(with({tls_policy(server_files())}));
  SteppedTlsClient c(h.port(), dir_.string(), "operator");
  ASSERT_TRUE(c.hello());
  ASSERT_TRUE(c.finish());
  ASSERT_TRUE(c.send(kReadHolding + kWriteSetpoint));
  c.shutdown_write();
  const Bytes read = c.reply();  // a read is answered at once, the write when it is done
  ASSERT_EQ(read.size(), 11u);
  EXPECT_EQ(Bytes(read.begin(), read.begin() + 2), (Bytes{0x00, 0x02}));
  EXPECT_EQ(c.reply(), kWriteSetpoint);
  EXPECT_TRUE(c.reply().empty());  // then closed
  EXPECT_TRUE(h.wait_clients(0));
}

TEST_F(Tls, HandshakesFromManyClientsAtOnceAllComplete) {
  Harness h(with({tls_policy(server_files())}));
  std::atomic<int> served{0};
  std::vector<std::thread> clients;
  for (int t = 0; t < 8; ++t) {
    clients.emplace_back([&] {
      for (int i = 0; i < 8; ++i) {
        if (exchange(h.port(), "operator", kReadHolding).size() == 11u) ++served;
      }
    });
  }
  for (auto& c : clients) c.join();
  EXPECT_EQ(served, 64);
  EXPECT_EQ(h.stats().tls_handshake_failures, 0u);
  EXPECT_TRUE(h.wait_clients(0));
}

// A connection keeps the context it started its handshake with: after a reload that trusts
// another CA, a handshake begun before it completes with the old one, new ones use the new one.
TEST_F(Tls, AReloadMidHandshakeLeavesTheHandshakeItsContext) {
  Harness h(with({tls_policy(server_files())}));
  SteppedTlsClient before(h.port(), dir_.string(), "operator");
  ASSERT_TRUE(before.hello());
  ListenerOptions next;
  next.host = "127.0.0.1";
  next.port = 0;
  next.policy = tls_policy(server_files());
  next.policy.tls->ca = dir_ / "other-ca.pem";
  const auto r = h.on_io([&] { return h.server().reload_listeners({next}); });
  EXPECT_TRUE(r.errors.empty());
  ASSERT_TRUE(before.finish());
  EXPECT_EQ(before.exchange(kReadHolding).size(), 11u);
  EXPECT_TRUE(exchange(h.port(), "operator", kReadHolding).empty());
  EXPECT_EQ(exchange(h.port(), "otherca", kReadHolding).size(), 11u);
}

// The server closed while handshakes wait on the handshake thread: every client is closed, the
// thread joined, nothing leaks (AddressSanitizer) or is used after it is gone.
TEST_F(Tls, StoppingTheServerWithHandshakesInFlightClosesThemAll) {
  std::vector<std::unique_ptr<SteppedTlsClient>> stalled;
  std::vector<std::unique_ptr<RawClient>> silent;
  {
    Harness h(with({tls_policy(server_files())}));
    for (int i = 0; i < 5; ++i) {
      stalled.push_back(std::make_unique<SteppedTlsClient>(h.port(), dir_.string(), "operator"));
      ASSERT_TRUE(stalled.back()->hello());
      silent.push_back(std::make_unique<RawClient>(h.port()));
    }
    EXPECT_TRUE(h.wait_clients(10));
  }
  EXPECT_FALSE(handshake_thread_runs());
  for (auto& c : silent) EXPECT_TRUE(c->closed_by_peer(3000ms));
  for (auto& c : stalled) {
    c->finish();  // TLS 1.3: the client may think it done; its request is never answered
    EXPECT_TRUE(c->exchange(kReadHolding).empty());
  }
}

}  // namespace
}  // namespace drivegate::modbus
