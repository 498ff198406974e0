// One Modbus master's line into drivegate's register map, in RTU or ASCII frames: a serial
// listener's port, or one RTU-over-TCP connection. It owns no descriptor: its owner hands it the
// bytes received (receive) and sends what it emits (Send). It finds requests (SlaveFramer),
// answers them through its own Dispatcher with the listener's session, as the Modbus TCP server
// does (the same access rules, validation and confirmed writes: no second way into a drive), and
// adds what only a serial line has: silence for units nobody here serves, broadcasts, FC 08.
//
// One request at a time, as a serial master asks. A write is answered when its drive took it
// (write_reply = confirmed) or as soon as it is validated and queued (accepted). A reply is never
// sent late: a master that sent anything since the request (a retry, the next request) has given
// up on it, so its reply is dropped and counted (no response), and the new request is served;
// so is a reply that could leave only after the master's response timeout (reply_timeout_ms),
// when the listener knows it.
// RTU on a line: a reply starts 3.5 characters after the request's last byte (reply_at).
#pragma once

#include <spdlog/logger.h>

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>

#include "config/config.h"  // WriteReply
#include "modbus/diagnostics.h"
#include "modbus/pdu.h"
#include "modbus/slave_framer.h"
#include "net/clock.h"
#include "net/log_throttle.h"

namespace drivegate::slave {

// What a listener's hosts share and may change on reload.
struct SlavePolicy {
  Session session;  // access, word order, source (kind, listener; client per host)
  WriteReply write_reply = WriteReply::confirmed;
  bool broadcast = false;   // apply writes sent to address 0 (to every unit that takes them)
  Millis reply_timeout{0};  // the master's response timeout (ListenerConfig::reply_timeout)
  friend bool operator==(const SlavePolicy& a, const SlavePolicy& b) {
    return a.session.access == b.session.access && a.session.word_order == b.session.word_order &&
           a.write_reply == b.write_reply && a.broadcast == b.broadcast &&
           a.reply_timeout == b.reply_timeout;
  }
};

// A listener's counters (every host of an RTU-over-TCP listener adds to the same), and where a
// master's FC 08 0x0A last cleared them (modbus/diagnostics.h). And the pace of the lines its
// masters can cause, shared likewise: a client connecting anew for every request gets no fresh
// burst of lines each time.
struct LineCounters {
  modbus::SerialCounters counts;
  modbus::SerialCounters cleared;
  net::LogThrottle denied_log;     // writes beyond the listener's access level
  net::LogThrottle broadcast_log;  // broadcasts refused
  net::LogThrottle late_log;       // replies dropped: too late, or the master asked again
  net::LogThrottle accepted_log;   // writes answered as accepted that then failed
};

class SlaveHost : public std::enable_shared_from_this<SlaveHost> {
 public:
  // A whole frame to put on the line, now.
  using Send = std::function<void(Bytes frame)>;

  SlaveHost(boost::asio::io_context& io, net::Clock& clock, modbus::Backend& backend,
            modbus::DeviceIdentity identity, modbus_serial::Framing framing,
            modbus::Delimit delimit, modbus::LineTiming timing,
            std::shared_ptr<const SlavePolicy> policy, LineCounters& counters,
            std::shared_ptr<spdlog::logger> log, std::string name, Send send);
  ~SlaveHost();
  SlaveHost(const SlaveHost&) = delete;
  SlaveHost& operator=(const SlaveHost&) = delete;

  void receive(ByteView bytes);
  // The line went and will come back (a port reopened): what is buffered is dropped, a write in
  // progress is left to settle unanswered.
  void reset();
  // The line is gone for good (listener closed, connection closed): reset, and nothing more is
  // sent.
  void stop();
  void set_policy(std::shared_ptr<const SlavePolicy> policy);
  // A request is waiting for its device, or its reply for its moment on the line.
  [[nodiscard]] bool busy() const { return pending_.has_value() || due_.has_value(); }
  // Called each time a request that waited for its device has been answered or given up on:
  // an owner waiting for the host to be done (a client that half-closed) looks again.
  void when_settled(std::function<void()> settled) { settled_ = std::move(settled); }
  // Part of a frame is held, waiting for the rest.
  [[nodiscard]] bool partial() const { return framer_.partial(); }

 private:
  struct Pending {
    std::uint32_t generation = 0;
    std::uint8_t unit = 0;
    Bytes request;  // the PDU
    bool forwarded = false;
    net::TimePoint reply_at{};
    // The master's response timeout (the policy's when the request came: a reload applies to
    // the requests after it), counted from the earliest moment a reply could leave (reply_at,
    // 3.5 characters after the request's end on the line): past it, no reply.
    Millis reply_timeout{0};
    std::optional<net::TimePoint> give_up_at;
  };
  // A write answered as accepted whose result is still to come (to tell of a failure).
  struct Accepted {
    std::uint8_t unit = 0;
    std::uint8_t function = 0;
  };

  void drain();
  void serve(modbus::FramerEvent& e);
  void serve_broadcast(const modbus_serial::Adu& adu);
  void reply(std::uint8_t unit, std::span<const std::uint8_t> pdu, net::TimePoint at);
  void on_done(std::uint32_t generation, modbus::Exception result,
               std::span<const std::uint8_t> forwarded_reply);
  // on_done's work, in a later turn of the event loop.
  void settle(std::uint32_t generation, modbus::Exception result, const Bytes& forwarded_reply);
  void superseded();
  // The pending request's reply would leave after the master's response timeout: dropped.
  void too_late(net::TimePoint would_leave);
  void arm();
  void on_timer(const boost::system::error_code& ec);
  void count_reply(std::span<const std::uint8_t> pdu);
  void put(Bytes frame);

  boost::asio::io_context& io_;
  net::Clock& clock_;
  modbus::Backend& backend_;
  modbus::Dispatcher dispatcher_;
  modbus_serial::Framing framing_;
  modbus::SlaveFramer framer_;
  std::shared_ptr<const SlavePolicy> policy_;
  // The policy's session with this host's own FaultReads (what its masters read of the drives'
  // faults), kept across a policy change.
  Session session_;
  LineCounters& line_;
  modbus::SerialCounters& counters_;  // line_.counts
  std::shared_ptr<spdlog::logger> log_;
  std::string name_;
  Send send_;
  std::function<void()> settled_;
  net::Timer timer_;
  bool timer_armed_ = false;
  net::TimePoint timer_at_ = net::TimePoint::max();

  std::optional<Pending> pending_;
  std::map<std::uint32_t, Accepted> accepted_;  // by generation, the oldest dropped past 64
  std::uint32_t generation_ = 0;
  // A reply waiting for its 3.5-character silence.
  std::optional<std::pair<net::TimePoint, Bytes>> due_;
  std::array<std::uint8_t, modbus::kMaxPduSize> out_{};
  std::array<std::uint8_t, modbus::kMaxPduSize> broadcast_out_{};
  bool stopped_ = false;
};

}  // namespace drivegate::slave
