// MQTT over TLS end to end (docs/mqtt.md, `broker = "mqtts://..."` with `ca`, `cert`, `key`): the
// real drivegated on simulated drives of the tests' own (test-drive), a real mosquitto broker on
// loopback with an mqtts listener that requires a client certificate (tests/support/mosquitto.h)
// and, on the same broker's plain listener, the independent Sparkplug host
// (tests/support/sparkplug_peer.h). The certificates are made at run time by
// tests/support/make_certs.sh in the test's own directory: ca (the plant's CA: the broker's
// server.pem and the client operator.pem), other-ca and otherca (a client certificate from that
// other CA), and otherhost (a server certificate from ca for other.example).
//
// What is shown: with the right files the daemon gets a session over TLS and the host sees the
// births and data; a broker that wants a client certificate refuses the daemon without one or with
// one from another CA; the daemon refuses a broker whose certificate does not chain to its `ca`,
// or does but names another host.
// In each refusal Modbus goes on being served, the host sees nothing of the node, and the daemon
// says why in its log and in /metrics and the status JSON. And a broker whose TCP handshake takes
// a while (any broker across a network) still gets its TLS handshake, and one that is down is
// told at once, without the daemon spinning.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <iterator>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "mqtt_e2e.h"

namespace drivegate::test {
namespace {

using namespace std::chrono_literals;
using ::testing::AllOf;
using ::testing::ContainsRegex;
using ::testing::HasSubstr;
using ::testing::Not;
namespace fs = std::filesystem;

// A TCP relay to 127.0.0.1:`to` whose first connection is established only on the client's SYN
// retransmission, a second after its connect(), as with a broker across a slow network: while the
// client's socket is still connecting, its first writes fail with EAGAIN (on loopback the
// handshake is over within connect() itself, and a client's TLS handshake never has to wait to
// write). Without privileges: the listening socket has a backlog of 0 and is kept full by a
// connection of the relay's own, so the kernel drops the client's SYN; once /proc/net/tcp shows
// the client in SYN_SENT, that connection is taken off the queue, and the retransmitted SYN gets
// through. Every connection is then relayed both ways as it comes.
class SlowConnectRelay {
 public:
  explicit SlowConnectRelay(int to) : to_(to) {
    listener_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof a;
    if (::bind(listener_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 ||
        ::listen(listener_, 0) != 0 ||
        ::getsockname(listener_, reinterpret_cast<sockaddr*>(&a), &len) != 0) {
      throw std::runtime_error("SlowConnectRelay: cannot listen");
    }
    port_ = ntohs(a.sin_port);
    filler_ = connect_loopback(port_);  // fills the accept queue
    if (filler_ < 0) throw std::runtime_error("SlowConnectRelay: cannot fill the queue");
    thread_ = std::thread([this] { run(); });
  }
  ~SlowConnectRelay() {
    stop_ = true;
    thread_.join();
    for (const int fd : {listener_, filler_}) {
      if (fd >= 0) ::close(fd);
    }
  }
  SlowConnectRelay(const SlowConnectRelay&) = delete;
  SlowConnectRelay& operator=(const SlowConnectRelay&) = delete;

  [[nodiscard]] int port() const { return port_; }
  // Whether a client was seen waiting in SYN_SENT (the slow start really happened).
  [[nodiscard]] bool client_waited() const { return client_waited_; }

 private:
  // Whether a socket of this machine is in SYN_SENT towards port_.
  bool syn_sent() const {
    std::ifstream tcp("/proc/net/tcp");
    std::string line;
    std::getline(tcp, line);  // the header
    while (std::getline(tcp, line)) {
      std::istringstream fields(line);
      std::string slot, local, remote, state;
      fields >> slot >> local >> remote >> state;
      const auto colon = remote.find(':');
      if (colon != std::string::npos && state == "02" &&
          std::stoi(remote.substr(colon + 1), nullptr, 16) == port_) {
        return true;
      }
    }
    return false;
  }

  void run() {
    const auto deadline = std::chrono::steady_clock::now() + 15s;
    while (!stop_ && !syn_sent() && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(5ms);
    }
    client_waited_ = syn_sent();
    // Room for the retransmitted SYN: the filler off the queue.
    const int queued = ::accept4(listener_, nullptr, nullptr, SOCK_CLOEXEC);
    if (queued >= 0) ::close(queued);
    std::vector<std::pair<int, int>> pairs;  // client, broker
    while (!stop_) {
      std::vector<pollfd> p{{listener_, POLLIN, 0}};
      for (const auto& [c, b] : pairs) {
        p.push_back({c, POLLIN, 0});
        p.push_back({b, POLLIN, 0});
      }
      if (::poll(p.data(), p.size(), 50) <= 0) continue;
      for (std::size_t i = 0; i < pairs.size(); ++i) {
        auto& [c, b] = pairs[i];
        bool open = true;
        for (const auto& [from, to] : {std::pair{c, b}, std::pair{b, c}}) {
          const short ev = p[1 + 2 * i + (from == c ? 0 : 1)].revents;
          if (ev == 0 || !open) continue;
          char buf[16384];
          const ssize_t n = ::read(from, buf, sizeof buf);
          open = n > 0 && ::write(to, buf, static_cast<std::size_t>(n)) == n;
        }
        if (!open) {
          ::close(c);
          ::close(b);
          c = b = -1;
        }
      }
      std::erase_if(pairs, [](const auto& x) { return x.first < 0; });
      if ((p[0].revents & POLLIN) != 0) {
        const int c = ::accept4(listener_, nullptr, nullptr, SOCK_CLOEXEC);
        const int b = c >= 0 ? connect_loopback(to_) : -1;
        if (b >= 0) {
          pairs.emplace_back(c, b);
        } else if (c >= 0) {
          ::close(c);
        }
      }
    }
    for (const auto& [c, b] : pairs) {
      ::close(c);
      ::close(b);
    }
  }

  int to_;
  int listener_ = -1;
  int filler_ = -1;
  int port_ = 0;
  std::atomic<bool> stop_{false};
  std::atomic<bool> client_waited_{false};
  std::thread thread_;
};

// The CPU time drivegated (`pid`) has used so far (utime + stime of /proc/PID/stat).
std::chrono::milliseconds cpu_time(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string stat((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::istringstream rest(stat.substr(stat.rfind(')') + 2));  // after "pid (comm) "
  std::string field;
  for (int i = 3; i <= 13; ++i) rest >> field;  // state .. cmajflt
  long utime = 0;
  long stime = 0;
  rest >> utime >> stime;
  return std::chrono::milliseconds((utime + stime) * 1000 / ::sysconf(_SC_CLK_TCK));
}

// How the daemon tells a broker's refusal of its client certificate
// (daemon/mqtt/mosquitto_client.cpp): with TLS 1.3 the client's side of the handshake is over
// before the broker checks the certificate, so the refusal is the TLS session ended before CONNACK.
constexpr const char* kRefusedByTheBroker =
    "the broker ended the TLS session before its CONNACK (is the client certificate refused?)";

// The MqttE2E fixture with a broker that has an mqtts listener requiring a client certificate
// from the test CA (its CN as the username) beside the plain one the peer uses; the daemon is
// given the mqtts one.
class MqttE2ETls : public MqttE2E {
 protected:
  void SetUp() override {
    if (const auto why = missing_dependency()) GTEST_SKIP() << *why;
    started_ = std::chrono::steady_clock::now();
    const Ran made = run_make_certs();
    ASSERT_EQ(made.status, 0) << made.err;
    ASSERT_TRUE(fs::exists(certs_ / "otherca.key"));
    start_broker("server");
    add_drive("drive-a");
    add_drive("drive-b");
  }

  // A broker presenting `server` (make_certs.sh's name) on its mqtts listener, and the peer on
  // its plain one; any before them are stopped (a test whose broker shows another certificate).
  void start_broker(const std::string& server) {
    peer_.reset();
    broker_.reset();
    broker_ = std::make_unique<Broker>(
        dir_, Broker::Tls{certs_ / "ca.pem", certs_ / (server + ".pem"), certs_ / (server + ".key"),
                          /*require_certificate=*/true, /*use_identity_as_username=*/true});
    SparkplugPeer::Options o;
    o.stderr_file = dir_ / "peer.log";
    peer_ = std::make_unique<SparkplugPeer>(broker_->port(), o);
  }

  // `ca = ...` and, unless `client` is empty, `cert` and `key` (make_certs.sh's names).
  [[nodiscard]] std::string tls_files(const std::string& ca, const std::string& client) const {
    std::string keys = "ca = \"" + (certs_ / (ca + ".pem")).string() + "\"\n";
    if (!client.empty()) {
      keys += "cert = \"" + (certs_ / (client + ".pem")).string() + "\"\nkey = \"" +
              (certs_ / (client + ".key")).string() + "\"\n";
    }
    return keys;
  }

  // MqttE2E::start_daemon, with the broker's mqtts URL (or `url`) in place of the plain one.
  void start_tls_daemon(const std::string& mqtt_extra, const std::string& url = "") {
    std::string toml = config(mqtt_extra);
    const std::string plain = "broker = \"" + broker_->url() + "\"";
    const auto at = toml.find(plain);
    ASSERT_NE(at, std::string::npos) << toml;
    toml.replace(at, plain.size(), "broker = \"" + (url.empty() ? broker_->tls_url() : url) + "\"");
    daemon_ = std::make_unique<Daemon>(dir_, toml, daemon_args_, dir_ / "drivegated.log");
    plc_ = std::make_unique<Plc>(daemon_->port());
    ASSERT_TRUE(plc_->connect());
    for (const auto& d : drives_) wait_online(d.unit);
  }

  // An [http] section for /metrics and the status JSON, on a free port (http_port_).
  std::string http_section() {
    http_port_ = free_port();
    return "\n[http]\nlisten = \"127.0.0.1:" + std::to_string(http_port_) + "\"\n";
  }

  // Reads both drives' status every 50 ms while `more` holds, for 10 s at most; every read must
  // be answered with the drive online.
  void serve_modbus_while(const std::function<bool()>& more) {
    int reads = 0;
    int failures = 0;
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    while (more() && std::chrono::steady_clock::now() < deadline) {
      for (const auto& d : drives_) {
        plc_->unit(d.unit);
        const auto r = plc_->input(reg::status, 1);
        ++reads;
        if (!r.ok() || (r.regs[0] & reg::online) == 0) ++failures;
      }
      std::this_thread::sleep_for(50ms);
    }
    EXPECT_GT(reads, 0);
    EXPECT_EQ(failures, 0) << "of " << reads << " Modbus reads while MQTT was refused";
  }
  // Until the broker has logged `refusal` `times` (each one an attempt of the daemon's turned
  // away).
  void serve_modbus_until_refused(const std::string& refusal, std::size_t times) {
    serve_modbus_while([&] { return occurrences(broker_log(), refusal) < times; });
    EXPECT_GE(occurrences(broker_log(), refusal), times)
        << "the broker did not log '" << refusal << "' " << times << " times";
  }

  // The "mqtt" object of the daemon's status JSON (one line of it).
  [[nodiscard]] std::string mqtt_status() const {
    const std::string body = http_get(http_port_, "/api/v1/status").body;
    const auto at = body.find("\"mqtt\": {");
    return at == std::string::npos ? body : body.substr(at, body.find('\n', at) - at);
  }

  // The daemon's first warning about the broker (one per outage, docs/mqtt.md), or "".
  [[nodiscard]] std::string warning(const std::string& log) const {
    const auto at = log.find("MQTT: " + broker_->tls_url() + ": ");
    return at == std::string::npos ? "" : log.substr(at, log.find('\n', at) - at);
  }

  // What every refusal shows: no session at the broker, nothing of the node at the host, the
  // daemon running with its drives served and one warning (one per outage, docs/mqtt.md) naming
  // the broker and `reason`, and /metrics and the status JSON not connected.
  void expect_no_session(const std::string& reason) {
    pump(300ms);
    EXPECT_EQ(sessions(), 0) << "the broker gave the daemon a session";
    for (const auto& m : peer_->history()) {
      EXPECT_FALSE(m.kind == "msg" && m.topic.starts_with(std::string("spBv1.0/") + kGroup + "/"))
          << "the host saw " << describe(m);
    }
    EXPECT_EQ(count("NBIRTH"), 0u);
    EXPECT_TRUE(daemon_->process().running());
    const std::string log = daemon_log();
    EXPECT_EQ(occurrences(log, "MQTT: " + broker_->tls_url() + ": "), 1u);
    EXPECT_THAT(warning(log), AllOf(HasSubstr(reason), HasSubstr("(Modbus is not affected)")));
    EXPECT_THAT(log, Not(HasSubstr("MQTT: connected")));
    EXPECT_EQ(metric(http_port_, "drivegate_mqtt_connected"), 0);
    EXPECT_EQ(metric(http_port_, "drivegate_mqtt_online"), 0);
    EXPECT_EQ(metric(http_port_, "drivegate_mqtt_connects_total"), 0);
    EXPECT_GE(metric(http_port_, "drivegate_mqtt_connection_losses_total"), 2);
    EXPECT_EQ(metric(http_port_, "drivegate_mqtt_device_births_total"), 0);
    EXPECT_THAT(mqtt_status(), AllOf(HasSubstr("\"connected\": false"),
                                     HasSubstr("\"session\": \"offline\""), HasSubstr(reason)));
  }

  fs::path certs_ = dir_ / "certs";
  int http_port_ = 0;

 private:
  struct Ran {
    int status = -1;
    std::string err;
  };
  Ran run_make_certs() const {
    const fs::path log = dir_ / "make_certs.log";
    Child child(
        {"/bin/sh", (fs::path(DRIVEGATE_SOURCE_DIR) / "tests/support/make_certs.sh").string(),
         certs_.string()},
        log);
    Ran r;
    r.status = child.wait_exit(30s);
    r.err = slurp(log);
    return r;
  }
};

// 1. The right CA and a client certificate from it: a session over TLS, the births and the data
// reach the host, and a DCMD comes back in over the same TLS session.
TEST_F(MqttE2ETls, ClientCertificateFromTheCaGetsASessionWithBirthsAndData) {
  ASSERT_NO_FATAL_FAILURE(start_tls_daemon(tls_files("ca", "operator") + "commands = true\n"));
  const Births b = wait_births();
  ASSERT_FALSE(HasFailure());
  EXPECT_EQ(b.node.topic, node_topic("NBIRTH"));
  EXPECT_EQ(b.node.seq, 0u);
  ASSERT_NE(b.node.metric("bdSeq"), nullptr) << describe(b.node);
  EXPECT_EQ(b.node.metric("bdSeq")->value, "0") << "the first attempt did not succeed";
  for (const auto& [name, m] : b.devices) {
    EXPECT_EQ(m.topic, device_topic("DBIRTH", name));
    ASSERT_NE(m.metric("status_online"), nullptr) << describe(m);
    EXPECT_EQ(m.metric("status_online")->value, "true");
  }

  // The session is the mqtts listener's, with the client certificate: the broker took the
  // daemon's identity from it (the configuration gives no username), and the daemon says so.
  const std::string blog = broker_log();
  EXPECT_EQ(sessions(), 1);
  EXPECT_THAT(blog, HasSubstr(" on port " + std::to_string(broker_->tls_port()) + "."));
  EXPECT_THAT(blog, HasSubstr(" as drivegate-gw01 (p2, c1, k30, u'operator')"));
  EXPECT_THAT(daemon_log(), HasSubstr("MQTT: connected to " + broker_->tls_url() +
                                      " as drivegate-gw01 (bdSeq 0)"));

  // Out: a PLC runs drive-a; DDATA carries the new speed. In: a DCMD stops it again.
  plc_->unit(1);
  ASSERT_EQ(plc_->write(reg::command, {1 /*run_forward*/, 600}), 0);
  ASSERT_TRUE(eventually([&] { return speed(1) == 600; }, 10s)) << speed(1);
  EXPECT_TRUE(peer_
                  ->wait_for(
                      [](const Message& m) {
                        return is(m, "DDATA", "drive-a") && m.metric("speed_rpm") != nullptr &&
                               m.metric("speed_rpm")->value == "600";
                      },
                      5s)
                  .has_value())
      << "no DDATA with speed_rpm 600";
  dcmd("drive-a", R"({"name":"command","type":"UInt16","value":0})");
  const auto r = wait_command_result("drive-a");
  ASSERT_TRUE(r.has_value()) << "the DCMD got no result";
  EXPECT_EQ(r->first, "command");
  EXPECT_EQ(r->second, "ok");
  EXPECT_TRUE(eventually([&] { return speed(1) == 0; }, 10s)) << speed(1);
  EXPECT_EQ(holding(1, reg::command), 0);
  expect_seq_consecutive(peer_->history());
  EXPECT_EQ(sessions(), 1) << "the session did not last";
}

// 2. The broker requires a client certificate and the daemon has none (`ca` alone is valid
// configuration): the broker ends every attempt in the TLS handshake; the daemon keeps retrying
// and keeps serving Modbus.
TEST_F(MqttE2ETls, WithoutAClientCertificateTheBrokerRefusesAndModbusIsServed) {
  ASSERT_NO_FATAL_FAILURE(start_tls_daemon(tls_files("ca", "") + http_section()));
  serve_modbus_until_refused("peer did not return a certificate", 2);
  expect_no_session(kRefusedByTheBroker);
}

// 2b. A client certificate the broker cannot chain to its CA: refused the same way.
TEST_F(MqttE2ETls, ClientCertificateFromAnotherCaIsRefusedByTheBroker) {
  ASSERT_NO_FATAL_FAILURE(start_tls_daemon(tls_files("ca", "otherca") + http_section()));
  serve_modbus_until_refused("certificate verify failed", 2);
  expect_no_session(kRefusedByTheBroker);
}

// 3. The daemon's `ca` is not the one that signed the broker's certificate: the daemon itself
// ends the handshake (the broker logs the daemon's "unknown ca" alert), with the right client
// certificate in hand.
TEST_F(MqttE2ETls, BrokerCertificateNotFromTheConfiguredCaIsRefusedByTheDaemon) {
  ASSERT_NO_FATAL_FAILURE(start_tls_daemon(tls_files("other-ca", "operator") + http_section()));
  serve_modbus_until_refused("alert unknown ca", 2);
  expect_no_session("certificate verify failed");
}

// 3b. The broker's certificate chains to the configured CA but is for another host (SAN
// DNS:other.example, not the 127.0.0.1 the daemon connects to): a CA signs for many hosts, and
// only the name tells this broker from any other server it has signed for. libmosquitto checks
// the name unless told not to (mosquitto_tls_insecure_set), inside OpenSSL's certificate check,
// so the daemon ends the handshake; OpenSSL's alert for it is a bare "internal error".
TEST_F(MqttE2ETls, BrokerCertificateForAnotherHostNameIsRefusedByTheDaemon) {
  ASSERT_NO_FATAL_FAILURE(start_broker("otherhost"));
  ASSERT_NO_FATAL_FAILURE(start_tls_daemon(tls_files("ca", "operator") + http_section()));
  serve_modbus_until_refused("alert internal error", 2);
  expect_no_session("host name verification failed");
}

// 4. A broker whose TCP handshake takes a second (any broker not on this machine takes some):
// the TLS handshake starts while the socket is still connecting, and must go on once it is
// connected. The session comes with the first attempt, about a second later, not after the
// attempt's 10 s timeout, and the daemon does not spin meanwhile.
TEST_F(MqttE2ETls, TlsHandshakeGoesOnAfterASlowTcpConnect) {
  SlowConnectRelay relay(broker_->tls_port());
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_NO_FATAL_FAILURE(start_tls_daemon(tls_files("ca", "operator"),
                                           "mqtts://127.0.0.1:" + std::to_string(relay.port())));
  const auto cpu0 = cpu_time(daemon_->process().pid());
  const auto nbirth = wait("NBIRTH", {}, 8s);
  const auto took =
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - t0);
  const auto cpu = cpu_time(daemon_->process().pid()) - cpu0;
  std::cerr << "NBIRTH " << took.count() << " ms after the start; drivegated used " << cpu.count()
            << " ms of CPU meanwhile\n";
  EXPECT_TRUE(relay.client_waited()) << "the daemon's connection was never seen in SYN_SENT";
  ASSERT_TRUE(nbirth.has_value()) << "no NBIRTH within 8 s";
  ASSERT_NE(nbirth->metric("bdSeq"), nullptr) << describe(*nbirth);
  EXPECT_EQ(nbirth->metric("bdSeq")->value, "0") << "the first attempt did not succeed";
  EXPECT_THAT(daemon_log(), Not(HasSubstr("no answer within")));
  EXPECT_THAT(broker_log(), HasSubstr(" as drivegate-gw01 (p2, c1, k30, u'operator')"));
  EXPECT_LT(cpu, took / 4) << "drivegated spun while connecting";
}

// 5. The broker down (its mqtts port closed): each attempt is refused at once, and says so (over
// TLS libmosquitto 2.0.11 would retry the refused handshake until the attempt's timeout, 10 s of a
// busy loop each); Modbus is served; once the broker is back, the next attempt has a session.
TEST_F(MqttE2ETls, BrokerDownIsRefusedAtOnceAndTheSessionComesBack) {
  broker_->stop();
  ASSERT_NO_FATAL_FAILURE(start_tls_daemon(tls_files("ca", "operator") + http_section()));
  const auto cpu0 = cpu_time(daemon_->process().pid());
  const auto t0 = std::chrono::steady_clock::now();
  // The attempts at the start, then 1 s and 3 s later at most (the back-off's random part):
  // refused.
  serve_modbus_while(
      [&] { return metric(http_port_, "drivegate_mqtt_connection_losses_total") < 3; });
  const auto span =
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - t0);
  const auto cpu = cpu_time(daemon_->process().pid()) - cpu0;
  std::cerr << "3 refused attempts; drivegated used " << cpu.count() << " ms of CPU in "
            << span.count() << " ms\n";
  EXPECT_GE(metric(http_port_, "drivegate_mqtt_connection_losses_total"), 3);
  EXPECT_LT(cpu, span / 4) << "drivegated spun while the broker was down";
  // Refused: by the kernel at connect() ("Connection refused") or in the TLS handshake.
  const std::string log = daemon_log();
  EXPECT_THAT(warning(log), AllOf(HasSubstr("refused"), HasSubstr("; retrying")));
  EXPECT_THAT(log, Not(HasSubstr("no answer within")));
  EXPECT_THAT(mqtt_status(), ContainsRegex("\"last_error\": \"[^\"]*refused"));

  broker_->start();
  ASSERT_TRUE(peer_->wait_for([](const Message& m) { return m.kind == "reconnected"; }, 5s))
      << "the peer did not reconnect";
  wait_births(10s);  // at the next attempt, at most 4 s after the third
  ASSERT_FALSE(HasFailure());
  EXPECT_EQ(sessions(), 1);
  EXPECT_EQ(metric(http_port_, "drivegate_mqtt_connected"), 1);
  EXPECT_EQ(metric(http_port_, "drivegate_mqtt_connects_total"), 1);
}

}  // namespace
}  // namespace drivegate::test
