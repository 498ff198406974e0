// End-to-end test support: a real MQTT broker, Debian's mosquitto, as a child process on a free
// loopback port, for the MQTT Sparkplug B northbound. Tests stop, restart (same port) and kill it
// to check how drivegate rides out a broker that goes away. tools/deps.sh installs mosquitto.
//
//   drivegate::test::TempDir dir;
//   drivegate::test::Broker broker(dir);             // plain MQTT on 127.0.0.1:broker.port()
//   broker.stop(); broker.start();                    // same port again
//
//   drivegate::test::Broker::Tls tls{certs / "ca.pem", certs / "server.pem", certs / "server.key"};
//   drivegate::test::Broker secure(dir, tls);         // and mqtts on 127.0.0.1:secure.tls_port()
//
// tests/support/make_certs.sh DIR makes the certificates (server.pem: CN=localhost, SAN
// 127.0.0.1). The broker's log (connections, errors) is in dir/"mosquitto.log", see log().
#pragma once

#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>

#include "e2e.h"

namespace drivegate::test {

class Broker {
 public:
  inline static const std::filesystem::path kMosquitto = "/usr/sbin/mosquitto";

  // An mqtts listener beside the plain one; the client certificate is asked for only with
  // `require_certificate` (then it must chain to `cafile`). `use_identity_as_username`: the
  // certificate's CN is the client's username (the log's "u'NAME'"), as a broker's ACLs use it.
  struct Tls {
    std::filesystem::path cafile;
    std::filesystem::path certfile;
    std::filesystem::path keyfile;
    bool require_certificate = false;
    bool use_identity_as_username = false;
  };

  // Writes dir/"mosquitto.conf" and starts the broker; throws if it does not accept TCP on its
  // port(s) within `timeout`.
  explicit Broker(const TempDir& dir, std::optional<Tls> tls = std::nullopt,
                  std::chrono::milliseconds timeout = std::chrono::seconds(10))
      : dir_(dir.path()), port_(free_port()), tls_(std::move(tls)), timeout_(timeout) {
    if (tls_) {
      do tls_port_ = free_port();
      while (tls_port_ == port_);
    }
    write_config();
    start();
  }
  ~Broker() = default;
  Broker(const Broker&) = delete;
  Broker& operator=(const Broker&) = delete;

  [[nodiscard]] int port() const { return port_; }
  // The mqtts port, 0 without TLS.
  [[nodiscard]] int tls_port() const { return tls_port_; }
  [[nodiscard]] std::string url() const { return "mqtt://127.0.0.1:" + std::to_string(port_); }
  [[nodiscard]] std::string tls_url() const {
    return "mqtts://127.0.0.1:" + std::to_string(tls_port_);
  }
  [[nodiscard]] std::filesystem::path config() const { return dir_ / "mosquitto.conf"; }
  [[nodiscard]] std::filesystem::path log_path() const { return dir_ / "mosquitto.log"; }
  // Everything the broker has logged so far (every start appends).
  [[nodiscard]] std::string log() const {
    std::ifstream in(log_path());
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
  [[nodiscard]] bool running() const { return child_ && child_->running(); }
  // The running broker's process id (its CPU and memory in /proc), -1 when stopped.
  [[nodiscard]] pid_t pid() const { return child_ ? child_->pid() : -1; }

  // Starts the broker again on the same port(s), if it is not running.
  void start() {
    if (running()) return;
    child_.reset();
    // mosquitto's own log_dest is stderr; the file is appended to across restarts by hand.
    const auto part = dir_ / "mosquitto.log.part";
    child_ = std::make_unique<Child>(
        std::vector<std::string>{kMosquitto.string(), "-c", config().string()}, part);
    const auto deadline = std::chrono::steady_clock::now() + timeout_;
    while (std::chrono::steady_clock::now() < deadline) {
      if (accepts(port_) && (tls_port_ == 0 || accepts(tls_port_))) return;
      if (!child_->running()) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    const bool exited = !child_->running();
    child_.reset();
    flush_log();
    throw std::runtime_error(kMosquitto.string() +
                             (exited ? " exited at start-up" : " did not listen") +
                             " on 127.0.0.1:" + std::to_string(port_) +
                             (tls_port_ ? " / " + std::to_string(tls_port_) : std::string()) +
                             " (is it installed? tools/deps.sh); its log:\n" + log());
  }
  // SIGTERM and waits; returns the exit status.
  int stop() { return end(SIGTERM); }
  // SIGKILL: the broker vanishes without closing anything cleanly.
  int kill() { return end(SIGKILL); }
  // stop() then start(): every client is disconnected and must reconnect and resubscribe
  // (persistence is off, so the broker forgets sessions and retained messages).
  void restart() {
    stop();
    start();
  }

 private:
  static bool accepts(int port) {
    const int fd = connect_loopback(port);
    if (fd < 0) return false;
    ::close(fd);
    return true;
  }

  int end(int sig) {
    if (!child_) return -1;
    const int status = child_->stop(sig);
    child_.reset();
    flush_log();
    return status;
  }

  // Child truncates its stderr file at each start: keep the whole history in mosquitto.log.
  void flush_log() {
    const auto part = dir_ / "mosquitto.log.part";
    std::ifstream in(part);
    std::ofstream(log_path(), std::ios::app) << in.rdbuf();
    std::error_code ec;
    std::filesystem::remove(part, ec);
  }

  void write_config() {
    std::ofstream c(config());
    c << "# Written by tests/support/mosquitto.h\n"
      << "per_listener_settings false\n"
      << "allow_anonymous true\n"
      << "persistence false\n"
      << "log_dest stderr\n"
      << "log_type error\nlog_type warning\nlog_type notice\nlog_type information\n"
      << "connection_messages true\n"
      // A host that must see every message: the default would drop a subscriber's messages
      // beyond 1000 queued (a fleet's replay burst at a host that is still decoding).
      << "max_queued_messages 0\n"
      << "log_timestamp_format %H:%M:%S\n";
    // Run as root (a test container), mosquitto would otherwise switch to the user "mosquitto",
    // who cannot read the 0600 keys make_certs.sh writes; as anybody else this line is ignored.
    if (::geteuid() == 0) c << "user root\n";
    c << "listener " << port_ << " 127.0.0.1\n";
    if (tls_) {
      c << "listener " << tls_port_ << " 127.0.0.1\n"
        << "cafile " << tls_->cafile.string() << "\n"
        << "certfile " << tls_->certfile.string() << "\n"
        << "keyfile " << tls_->keyfile.string() << "\n"
        << "require_certificate " << (tls_->require_certificate ? "true" : "false") << "\n"
        << "use_identity_as_username " << (tls_->use_identity_as_username ? "true" : "false")
        << "\n";
    }
    if (!c) throw std::runtime_error("cannot write " + config().string());
  }

  std::filesystem::path dir_;
  int port_;
  int tls_port_ = 0;
  std::optional<Tls> tls_;
  std::chrono::milliseconds timeout_;
  std::unique_ptr<Child> child_;
};

}  // namespace drivegate::test
