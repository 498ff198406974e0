#include "mqtt/mosquitto_client.h"

#include <mosquitto.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <openssl/ssl.h>
#include <sys/ioctl.h>
#include <sys/socket.h>

#include <boost/asio/ip/address.hpp>
#include <boost/asio/post.hpp>
#include <cerrno>
#include <cstring>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <utility>

namespace drivegate::mqtt {

namespace asio = boost::asio;

namespace {

constexpr std::chrono::seconds kMiscPeriod{1};  // keep-alive pings and their timeouts
constexpr int kPacketsPerTurn = 64;             // read at most this many before letting others run
// How a broker's refusal of the client certificate shows (MosquittoClient::lost_reason).
constexpr const char* kEndedBeforeConnack =
    "the broker ended the TLS session before its CONNACK (is the client certificate refused?): ";

// libmosquitto's process-wide set-up, done once before the first client (its documented
// requirement); never undone, as other clients may still be alive at exit.
void init_library() {
  static std::once_flag once;
  std::call_once(once, [] { mosquitto_lib_init(); });
}

std::string error_text(int rc) {
  if (rc == MOSQ_ERR_ERRNO) return std::strerror(errno);
  return mosquitto_strerror(rc);
}

bool is_address(const std::string& host) {
  boost::system::error_code ec;
  asio::ip::make_address(host, ec);
  return !ec;
}

// The attempt's TLS handshake while it is not over, else nullptr. libmosquitto 2.0.11 (Debian 12)
// goes on with it only in mosquitto_loop_read, whichever way OpenSSL waits: its loop_write does
// nothing until the handshake is over, while mosquitto_want_write says yes (the CONNECT is queued
// behind it). Over any network but loopback, the handshake's first write finds the TCP connection
// still being set up (EAGAIN): waiting to write and calling loop_write would spin until the
// attempt's timeout (tests/e2e/mqtt_tls_e2e_test.cpp, TlsHandshakeGoesOnAfterASlowTcpConnect).
const SSL* handshaking(mosquitto* m) {
  const auto* ssl = static_cast<const SSL*>(mosquitto_ssl_get(m));
  return ssl != nullptr && SSL_is_init_finished(ssl) == 0 ? ssl : nullptr;
}

// Why the TLS handshake cannot go on, or nullopt. libmosquitto 2.0.11 takes OpenSSL's
// SSL_ERROR_SYSCALL in the handshake (the connection refused, or closed by the broker) for "try
// again" (its issue 2594): the socket then stays ready, and the attempt would spin until its
// timeout, for a broker that is down too. The TCP state tells.
std::optional<std::string> handshake_ended(mosquitto* m) {
  if (handshaking(m) == nullptr) return std::nullopt;
  tcp_info info{};
  socklen_t size = sizeof info;
  if (::getsockopt(mosquitto_socket(m), IPPROTO_TCP, TCP_INFO, &info, &size) != 0) {
    return std::nullopt;
  }
  if (info.tcpi_state == TCP_CLOSE) return "the connection was refused or reset";
  if (info.tcpi_state == TCP_CLOSE_WAIT) return "the broker closed the connection in TLS set-up";
  return std::nullopt;
}

}  // namespace

MosquittoClient::MosquittoClient(asio::io_context& io, BrokerOptions options, Handlers handlers,
                                 std::shared_ptr<spdlog::logger> log)
    : io_(io),
      options_(std::move(options)),
      handlers_(std::move(handlers)),
      log_(std::move(log)),
      resolver_(io),
      socket_(io),
      misc_timer_(io),
      connect_timer_(io),
      confirm_timer_(io) {
  init_library();
  mosq_ = mosquitto_new(options_.client_id.c_str(), true, this);
  if (mosq_ == nullptr) throw std::runtime_error("mosquitto_new failed");
  setup_error_ = configure();
  if (!setup_error_.empty()) throw std::runtime_error(setup_error_);
}

void MosquittoClient::use_broker(BrokerOptions options) {
  state_ = State::idle;
  connect_timer_.cancel();
  close_socket();
  options_ = std::move(options);
  // Back to a new client's settings (TLS off included), the socket closed, then this broker's.
  const int rc = mosquitto_reinitialise(mosq_, options_.client_id.c_str(), true, this);
  setup_error_ = rc == MOSQ_ERR_SUCCESS ? configure() : "MQTT client: " + error_text(rc);
}

std::string MosquittoClient::configure() {
  mosquitto_connect_callback_set(mosq_, &MosquittoClient::on_connect);
  mosquitto_disconnect_callback_set(mosq_, &MosquittoClient::on_disconnect);
  mosquitto_message_callback_set(mosq_, &MosquittoClient::on_message);
  mosquitto_unsubscribe_callback_set(mosq_, &MosquittoClient::on_unsubscribe);
  mosquitto_log_callback_set(mosq_, &MosquittoClient::on_log);
  mosquitto_int_option(mosq_, MOSQ_OPT_TCP_NODELAY, 1);  // a DDATA leaves at once, not batched
  const auto failed = [](int rc, const char* what) {
    return rc == MOSQ_ERR_SUCCESS ? std::string()
                                  : std::string("MQTT ") + what + ": " + error_text(rc);
  };
  if (!options_.username.empty()) {
    const int rc =
        mosquitto_username_pw_set(mosq_, options_.username.c_str(),
                                  options_.password.empty() ? nullptr : options_.password.c_str());
    if (rc != MOSQ_ERR_SUCCESS) return failed(rc, "username");
  }
  if (options_.tls) {
    int rc = mosquitto_tls_set(mosq_, options_.ca.c_str(), nullptr,
                               options_.cert.empty() ? nullptr : options_.cert.c_str(),
                               options_.key.empty() ? nullptr : options_.key.c_str(), nullptr);
    if (rc != MOSQ_ERR_SUCCESS) return failed(rc, "TLS files");
    rc = mosquitto_tls_opts_set(mosq_, SSL_VERIFY_PEER, "tlsv1.2", nullptr);
    if (rc != MOSQ_ERR_SUCCESS) return failed(rc, "TLS options");
  }
  return {};
}

MosquittoClient::~MosquittoClient() {
  state_ = State::idle;
  // Closing the socket cancels asio's wait on it, which reports a failure by throwing; a
  // destructor has no one to tell, and the client is destroyed whatever happened.
  try {
    close_socket();
  } catch (...) {  // nothing to do but to go on
  }
  mosquitto_destroy(mosq_);
}

void MosquittoClient::connect(const std::string& will_topic, const std::string& will_payload) {
  state_ = State::idle;
  close_socket();
  will_topic_ = will_topic;
  will_payload_ = will_payload;
  lib_error_.clear();
  if (!setup_error_.empty()) {  // this broker's settings were refused (a TLS file gone)
    state_ = State::connecting;
    fail(setup_error_);
    return;
  }
  connect_timer_.expires_after(options_.connect_timeout);
  const std::uint64_t generation = generation_;
  connect_timer_.async_wait([this, generation](const boost::system::error_code& ec) {
    if (ec || generation != generation_ || state_ == State::connected || state_ == State::idle) {
      return;
    }
    fail("no answer within " + std::to_string(options_.connect_timeout.count()) + " ms");
  });
  // A name is looked up here, on the loop without waiting; TLS still hands libmosquitto the name
  // (its certificate check needs it), which it then looks up again.
  if (is_address(options_.host)) {
    start(options_.host);
    return;
  }
  state_ = State::resolving;
  resolver_.async_resolve(
      options_.host, std::to_string(options_.port),
      [this, generation](const boost::system::error_code& ec,
                         const asio::ip::tcp::resolver::results_type& results) {
        if (generation != generation_ || state_ != State::resolving) return;
        if (ec || results.empty()) {
          fail("cannot resolve " + options_.host + ": " + ec.message());
          return;
        }
        start(options_.tls ? options_.host : results.begin()->endpoint().address().to_string());
      });
}

void MosquittoClient::start(const std::string& address) {
  state_ = State::connecting;
  int rc = will_topic_.empty() ? mosquitto_will_clear(mosq_)
                               : mosquitto_will_set(mosq_, will_topic_.c_str(),
                                                    static_cast<int>(will_payload_.size()),
                                                    will_payload_.data(), 1, false);
  if (rc == MOSQ_ERR_SUCCESS) {
    rc = mosquitto_connect_async(mosq_, address.c_str(), options_.port,
                                 static_cast<int>(options_.keepalive.count()));
  }
  if (rc != MOSQ_ERR_SUCCESS) {
    fail(lost_reason(rc));
    return;
  }
  const int fd = mosquitto_socket(mosq_);
  if (fd < 0) {
    fail("no socket");
    return;
  }
  boost::system::error_code ec;
  socket_.assign(fd, ec);
  if (ec) {
    fail("cannot watch the socket: " + ec.message());
    return;
  }
  watch();
  tick();
}

void MosquittoClient::watch() {
  if (state_ == State::idle || state_ == State::resolving || !socket_.is_open()) return;
  const std::uint64_t generation = generation_;
  if (!reading_) {
    reading_ = true;
    socket_.async_wait(asio::posix::stream_descriptor::wait_read,
                       [this, generation](const boost::system::error_code& ec) {
                         if (generation != generation_) return;
                         reading_ = false;
                         if (!ec) on_readable(generation);
                       });
  }
  const SSL* tls = handshaking(mosq_);
  if (!writing_ && (tls != nullptr ? SSL_want_write(tls) != 0 : mosquitto_want_write(mosq_))) {
    writing_ = true;
    socket_.async_wait(asio::posix::stream_descriptor::wait_write,
                       [this, generation](const boost::system::error_code& ec) {
                         if (generation != generation_) return;
                         writing_ = false;
                         if (!ec) on_writable(generation);
                       });
  }
}

// Asio's reactor is edge-triggered: everything already readable is read now (the socket's bytes
// and what TLS decrypted ahead), or a packet would wait for the next one to arrive.
void MosquittoClient::on_readable(std::uint64_t generation) {
  for (int i = 0; i < kPacketsPerTurn; ++i) {
    const int rc = mosquitto_loop_read(mosq_, 1);
    if (generation != generation_) return;  // a callback ended or replaced the session
    if (rc != MOSQ_ERR_SUCCESS) {
      fail(lost_reason(rc));
      return;
    }
    if (auto ended = handshake_ended(mosq_)) {
      fail(std::move(*ended));
      return;
    }
    int pending = 0;
    const int fd = mosquitto_socket(mosq_);
    if (fd >= 0) ::ioctl(fd, FIONREAD, &pending);
    if (const auto* ssl = static_cast<SSL*>(mosquitto_ssl_get(mosq_)); ssl != nullptr) {
      pending += SSL_pending(ssl);
    }
    if (pending <= 0) {
      watch();
      return;
    }
  }
  watch();
  asio::post(io_, [this, generation] {
    if (generation == generation_) on_readable(generation);
  });
}

void MosquittoClient::on_writable(std::uint64_t generation) {
  const int rc = handshaking(mosq_) != nullptr ? mosquitto_loop_read(mosq_, 1)  // its next step
                                               : mosquitto_loop_write(mosq_, 1);
  if (generation != generation_) return;
  if (rc != MOSQ_ERR_SUCCESS) {
    fail(lost_reason(rc));
    return;
  }
  if (auto ended = handshake_ended(mosq_)) {
    fail(std::move(*ended));
    return;
  }
  watch();
}

void MosquittoClient::tick() {
  misc_timer_.expires_after(kMiscPeriod);
  const std::uint64_t generation = generation_;
  misc_timer_.async_wait([this, generation](const boost::system::error_code& ec) {
    if (ec || generation != generation_ || state_ == State::idle) return;
    const int rc = mosquitto_loop_misc(mosq_);
    if (generation != generation_) return;
    if (rc != MOSQ_ERR_SUCCESS && rc != MOSQ_ERR_NO_CONN) {
      fail(lost_reason(rc));
      return;
    }
    watch();  // a ping may have been queued
    tick();
  });
}

bool MosquittoClient::publish(const std::string& topic, const std::string& payload, int qos,
                              bool retain) {
  if (state_ != State::connected) return false;
  const int rc = mosquitto_publish(mosq_, nullptr, topic.c_str(), static_cast<int>(payload.size()),
                                   payload.data(), qos, retain);
  if (rc != MOSQ_ERR_SUCCESS) {
    log_->warn("MQTT: publish to {} failed: {}", topic, error_text(rc));
    return false;
  }
  ++published_;
  confirm_later();
  watch();
  return true;
}

void MosquittoClient::confirm_later() {
  if (!asks_broker() || question_ || confirm_armed_ || state_ != State::connected ||
      confirmed_ >= published_) {
    return;
  }
  confirm_armed_ = true;
  confirm_timer_.expires_after(kConfirmDelay);
  const std::uint64_t generation = generation_;
  confirm_timer_.async_wait([this, generation](const boost::system::error_code& ec) {
    if (ec || generation != generation_ || !confirm_armed_) return;
    confirm_armed_ = false;
    ask_broker();
  });
}

void MosquittoClient::confirm_now() {
  if (question_ || state_ != State::connected || confirmed_ >= published_) return;
  if (confirm_armed_) {
    confirm_armed_ = false;
    confirm_timer_.cancel();
  }
  ask_broker();
}

void MosquittoClient::ask_broker() {
  if (!asks_broker() || state_ != State::connected || question_ || confirmed_ >= published_) {
    return;
  }
  int mid = 0;
  // Never subscribed to: the broker answers, and nothing changes (MQTT 3.1.1 section 3.10.4).
  const int rc = mosquitto_unsubscribe(mosq_, &mid, will_topic_.c_str());
  if (rc != MOSQ_ERR_SUCCESS) {
    fail(lost_reason(rc));
    return;
  }
  question_ = mid;
  question_covers_ = published_;
  confirm_timer_.expires_after(kAckTimeout);
  const std::uint64_t generation = generation_;
  confirm_timer_.async_wait([this, generation, mid](const boost::system::error_code& ec) {
    if (ec || generation != generation_ || question_ != mid) return;
    fail("the broker confirmed nothing within " + std::to_string(kAckTimeout.count() / 1000) +
         " s: the link is dead");
  });
  watch();
}

void MosquittoClient::on_unsubscribe(mosquitto* /*m*/, void* self, int mid) {
  auto* c = static_cast<MosquittoClient*>(self);
  if (c->question_ != mid) return;
  c->question_.reset();
  c->confirm_timer_.cancel();
  c->confirmed_ = c->question_covers_;
  const std::uint64_t generation = c->generation_;
  if (c->handlers_.delivered) c->handlers_.delivered(c->confirmed_);
  if (generation == c->generation_) c->confirm_later();
}

bool MosquittoClient::subscribe(const std::string& topic, int qos) {
  if (state_ != State::connected) return false;
  const int rc = mosquitto_subscribe(mosq_, nullptr, topic.c_str(), qos);
  if (rc != MOSQ_ERR_SUCCESS) {
    log_->warn("MQTT: subscribe to {} failed: {}", topic, error_text(rc));
    return false;
  }
  watch();
  return true;
}

bool MosquittoClient::busy() const {
  return state_ == State::connected && mosquitto_want_write(mosq_);
}

void MosquittoClient::disconnect() {
  const bool was_connected = state_ == State::connected;
  state_ = State::idle;
  connect_timer_.cancel();
  // DISCONNECT goes out before the socket closes: the broker then forgets the will.
  if (was_connected) mosquitto_disconnect(mosq_);
  close_socket();
}

std::string MosquittoClient::lost_reason(int rc) const {
  const int err = errno;           // for MOSQ_ERR_ERRNO, as libmosquitto left it
  if (rc == MOSQ_ERR_KEEPALIVE) {  // libmosquitto 2.0.11 has no text for it ("Unknown error.")
    return std::string(state_ == State::connecting ? "no CONNACK" : "no answer to a PINGREQ") +
           " from the broker within the keep-alive (" + std::to_string(options_.keepalive.count()) +
           " s): the link is dead";
  }
  std::string why = rc == MOSQ_ERR_ERRNO ? std::strerror(err) : mosquitto_strerror(rc);
  // With TLS 1.3 the client's side of the handshake is over before the broker has checked the
  // client certificate: a broker that does not accept it ends the session before CONNACK, which
  // libmosquitto reports as a lost connection (or EPROTO, EPIPE, ECONNRESET: its TLS read or the
  // CONNECT's write failed). Its own certificate check failing is MOSQ_ERR_TLS.
  const bool ended = rc == MOSQ_ERR_CONN_LOST ||
                     (rc == MOSQ_ERR_ERRNO && (err == EPROTO || err == EPIPE || err == ECONNRESET));
  if (options_.tls && state_ == State::connecting && ended) {
    why = kEndedBeforeConnack + why;
  }
  return why;
}

void MosquittoClient::fail(std::string why) {
  if (state_ == State::idle) return;
  if (!lib_error_.empty()) why += " (" + std::exchange(lib_error_, {}) + ")";
  state_ = State::idle;
  connect_timer_.cancel();
  close_socket();
  if (handlers_.lost) handlers_.lost(std::move(why));
}

void MosquittoClient::close_socket() {
  ++generation_;
  reading_ = false;
  writing_ = false;
  question_.reset();  // what it did not confirm stays unconfirmed: the owner keeps it
  confirm_armed_ = false;
  confirm_timer_.cancel();
  resolver_.cancel();
  misc_timer_.cancel();
  if (socket_.is_open()) socket_.release();  // libmosquitto owns the descriptor
}

void MosquittoClient::on_connect(mosquitto* /*m*/, void* self, int rc) {
  auto* c = static_cast<MosquittoClient*>(self);
  if (c->state_ != State::connecting) return;
  if (rc != 0) {
    c->fail(std::string("broker refused the connection: ") + mosquitto_connack_string(rc));
    return;
  }
  c->state_ = State::connected;
  c->confirmed_ = c->published_;  // a new session: nothing of an earlier one waits here
  c->connect_timer_.cancel();
  c->lib_error_.clear();
  if (c->handlers_.connected) c->handlers_.connected();
}

void MosquittoClient::on_disconnect(mosquitto* /*m*/, void* self, int rc) {
  auto* c = static_cast<MosquittoClient*>(self);
  c->fail(rc == 0 ? std::string("disconnected by the broker") : c->lost_reason(rc));
}

// libmosquitto only logs OpenSSL's reasons ("certificate verify failed", ...): the attempt's first
// error is kept for lost.
void MosquittoClient::on_log(mosquitto* /*m*/, void* self, int level, const char* text) {
  auto* c = static_cast<MosquittoClient*>(self);
  if (level == MOSQ_LOG_ERR && text != nullptr && c->lib_error_.empty()) c->lib_error_ = text;
}

void MosquittoClient::on_message(mosquitto* /*m*/, void* self, const mosquitto_message* msg) {
  auto* c = static_cast<MosquittoClient*>(self);
  if (c->handlers_.message == nullptr || msg->topic == nullptr) return;
  c->handlers_.message(msg->topic,
                       std::string_view(static_cast<const char*>(msg->payload),
                                        static_cast<std::size_t>(std::max(msg->payloadlen, 0))),
                       msg->retain);
}

}  // namespace drivegate::mqtt
