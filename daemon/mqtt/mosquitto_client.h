// An MQTT 3.1.1 client session on the daemon's event loop: libmosquitto (Debian's
// libmosquitto-dev) does the protocol; this class gives it the loop (a read and, while it has
// bytes queued, a write wait on its socket, and a one-second timer for keep-alive), so nothing
// ever blocks on the broker. One connection attempt at a time; what to do when it is lost
// (back-off, a new will) is the owner's (northbound.cpp).
//
// Delivery: a QoS 0 message handed to libmosquitto is only queued, and a link that went half-open
// (the broker gone without a FIN or RST: a cable, a NAT, a firewall's state) takes every one of
// them until keep-alive notices, one to two keep-alives later. So the client asks the broker to
// confirm what it has received: kConfirmDelay after a message that is not confirmed yet, it sends
// an UNSUBSCRIBE of a topic it never subscribes to (its own will's), which the broker must answer
// (MQTT 3.1.1 section 3.10.4) after reading everything sent before it on the connection: its
// UNSUBACK proves every message before it arrived (Handlers::delivered). One such question is out
// at a time. Unanswered for kAckTimeout, the link is taken for dead and the session ends (lost):
// a dead link is detected at most kConfirmDelay + kAckTimeout after the first message published
// on it; with nothing published, keep-alive detects it as before. A client with no will (a
// tool's) or no Handlers::delivered asks nothing: it has no topic that is surely its own to ask
// with, or nobody to tell.
#pragma once

#include <spdlog/logger.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/posix/stream_descriptor.hpp>
#include <boost/asio/steady_timer.hpp>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

struct mosquitto;
struct mosquitto_message;

namespace drivegate::mqtt {

inline constexpr std::chrono::milliseconds kConfirmDelay{250};
inline constexpr std::chrono::milliseconds kAckTimeout{5'000};

struct BrokerOptions {
  std::string host;  // an address; a name is resolved before each attempt, off the loop's path
  std::uint16_t port = 1883;
  bool tls = false;
  std::string ca;  // TLS: the CA that signed the broker's certificate
  std::string cert;
  std::string key;  // TLS client certificate and key, both or neither
  std::string client_id;
  std::string username;  // empty: none
  std::string password;
  std::chrono::seconds keepalive{30};
  std::chrono::milliseconds connect_timeout{10'000};  // TCP, TLS and CONNACK together
};

class MosquittoClient {
 public:
  struct Handlers {
    std::function<void()> connected;            // CONNACK accepted
    std::function<void(std::string why)> lost;  // an attempt failed or the session ended
    // `retained`: from the broker's store at subscription, not published now.
    std::function<void(std::string_view topic, std::string_view payload, bool retained)> message;
    // The broker has received every message publish() took up to number `up_to` (published()).
    std::function<void(std::uint64_t up_to)> delivered;
  };

  MosquittoClient(boost::asio::io_context& io, BrokerOptions options, Handlers handlers,
                  std::shared_ptr<spdlog::logger> log);
  ~MosquittoClient();
  MosquittoClient(const MosquittoClient&) = delete;
  MosquittoClient& operator=(const MosquittoClient&) = delete;

  // From the next connect() on, this broker (another of [mqtt] brokers): an attempt or session
  // in progress is abandoned (without calling lost), and the client set up afresh for it.
  void use_broker(BrokerOptions options);
  // Starts an attempt with this will (QoS 1, not retained; an empty topic: none, as for a tool
  // that only sends a command); connected or lost follows. An attempt or session in progress is
  // abandoned first (without calling lost).
  void connect(const std::string& will_topic, const std::string& will_payload);
  // Queues a message; false (nothing queued) when there is no session. Each message taken is
  // numbered, one on from the last, over every session: published() is the last one's number.
  bool publish(const std::string& topic, const std::string& payload, int qos, bool retain);
  [[nodiscard]] std::uint64_t published() const { return published_; }
  // Asks the broker to confirm what it has not yet now, without waiting for kConfirmDelay (when
  // no question is out already).
  void confirm_now();
  bool subscribe(const std::string& topic, int qos);
  // Ends the session cleanly (DISCONNECT: the broker drops the will). lost is not called.
  void disconnect();

  [[nodiscard]] bool connected() const { return state_ == State::connected; }
  // Bytes queued for the broker and not yet written: it is slower than what is published.
  [[nodiscard]] bool busy() const;
  [[nodiscard]] const BrokerOptions& options() const { return options_; }

 private:
  enum class State : std::uint8_t { idle, resolving, connecting, connected };

  void start(const std::string& address);
  void watch();
  void on_readable(std::uint64_t generation);
  void on_writable(std::uint64_t generation);
  void tick();
  // Delivery (above): the next question to the broker once kConfirmDelay has passed, if messages
  // wait for one and none is out.
  void confirm_later();
  void ask_broker();
  // Whether it asks at all: with a will's topic to ask by, and someone to tell (above).
  [[nodiscard]] bool asks_broker() const {
    return !will_topic_.empty() && static_cast<bool>(handlers_.delivered);
  }
  void fail(std::string why);
  // libmosquitto's `rc` (and errno) as the reason an attempt or session ended.
  [[nodiscard]] std::string lost_reason(int rc) const;
  void close_socket();
  // Callbacks, options, credentials and TLS on a new or reinitialised client; why not, or "".
  std::string configure();
  static void on_connect(mosquitto* m, void* self, int rc);
  static void on_disconnect(mosquitto* m, void* self, int rc);
  static void on_message(mosquitto* m, void* self, const mosquitto_message* msg);
  static void on_unsubscribe(mosquitto* m, void* self, int mid);
  static void on_log(mosquitto* m, void* self, int level, const char* text);

  boost::asio::io_context& io_;
  BrokerOptions options_;
  Handlers handlers_;
  std::shared_ptr<spdlog::logger> log_;
  mosquitto* mosq_ = nullptr;
  boost::asio::ip::tcp::resolver resolver_;
  boost::asio::posix::stream_descriptor socket_;
  boost::asio::steady_timer misc_timer_;
  boost::asio::steady_timer connect_timer_;
  boost::asio::steady_timer confirm_timer_;  // the next question, or the answer's deadline
  State state_ = State::idle;
  std::uint64_t generation_ = 0;  // bumped whenever the socket changes: older waits are stale
  bool reading_ = false;
  bool writing_ = false;
  std::string setup_error_;  // configure()'s refusal: every attempt fails with it
  std::string will_topic_;
  std::string will_payload_;
  std::string lib_error_;        // libmosquitto's first error message in this attempt (OpenSSL's)
  std::uint64_t published_ = 0;  // messages taken, over every session
  std::uint64_t confirmed_ = 0;  // the broker received every message up to this one
  std::optional<int> question_;  // the UNSUBSCRIBE out (its message id), if any
  std::uint64_t question_covers_ = 0;  // the last message sent before it
  bool confirm_armed_ = false;         // confirm_timer_ waits for the next question
};

}  // namespace drivegate::mqtt
