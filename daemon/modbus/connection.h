// One Modbus TCP client. Reads large chunks into a fixed buffer, dispatches every complete request
// in it, gathers the replies of one read batch into one socket write, and answers reads at once
// even while earlier writes of the same connection wait for their device (Modbus TCP matches
// replies by transaction id, so replies may leave out of order). Closes on a malformed MBAP
// header (after sending the replies already queued), on a partial frame older than
// frame_timeout, and after idle_timeout without a request. A client that half-closes (shutdown
// SHUT_WR, or a TLS close_notify) has said all it will: every request it sent is still carried
// out and answered, then the connection closes. A write whose client has gone before its result
// is counted (writes_unanswered) and logged, never dropped silently. Both timeouts are read from
// the shared ServerState when a deadline is computed, so new values (Server::set_limits) apply to
// an open connection, measured from its last request or partial frame as before.
//
// On a TLS listener the connection first has the server's handshake thread complete the
// handshake (handshaker.h: the client certificate is verified by OpenSSL against the listener's
// CA, off the event loop), takes its access level from the certificate's role, and only then
// reads requests, through TLS on its own socket (tls_stream.h): nothing is read in clear text on
// a TLS listener. While the handshake thread has the socket, the connection only ever shuts it
// down; it closes it once the thread has handed it back.
#pragma once

#include <array>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/ssl/context.hpp>
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "mbap.h"
#include "server_state.h"
#include "tls_stream.h"

namespace drivegate::modbus {

class Connection : public std::enable_shared_from_this<Connection> {
 public:
  Connection(std::shared_ptr<ServerState> state, std::shared_ptr<ListenerState> listener,
             boost::asio::ip::tcp::socket socket);
  ~Connection();
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  void start();
  // Closes the socket at once; writes still pending at the backend are answered into the void.
  void close();
  // The server's idle_timeout or frame_timeout changed: moves the timer earlier when the new
  // values bring the next deadline forward (a later one is found when the armed timer fires).
  // Never closes the connection itself: the timer does, in a later turn of the event loop.
  void limits_changed();
  // The listener's policy changed (reload): the access level and word order are worked out again
  // (for a TLS client, from the role its certificate carried); a client whose address is no
  // longer allowed is closed.
  void policy_changed();
  // Whether this connection may be closed to make room on its full listener, and since when it
  // has been idle: a read-only session (after any TLS handshake) with no write pending and no
  // partial frame. Operate and maintain sessions never give way.
  [[nodiscard]] std::optional<net::TimePoint> evictable_since() const;
  [[nodiscard]] const ListenerState& listener() const { return *listener_; }
  // Closes it for a newer client on its full listener (counted, and logged by the server).
  void evict();

 private:
  // A write request waiting for its device. The request PDU is kept to build the response.
  struct PendingWrite {
    bool used = false;
    bool done = false;
    Exception result = Exception::none;
    std::uint32_t generation = 0;
    std::uint16_t transaction = 0;
    std::uint8_t unit = 0;
    std::uint8_t size = 0;
    std::array<std::uint8_t, kMaxPduSize> request{};
    // Forwarded to a pass-through device (Dispatcher::forward): answered with its reply.
    bool forwarded = false;
    std::uint8_t reply_size = 0;
    std::array<std::uint8_t, kMaxPduSize> reply{};
  };

  void on_handshake(HandshakeResult result);
  void apply_policy();
  void read();
  void on_read(const boost::system::error_code& ec, std::size_t n);
  void process_input(net::TimePoint now);
  void dispatch(const MbapHeader& header, std::span<const std::uint8_t> pdu);
  std::span<std::uint8_t> reserve_reply();
  void commit_reply(std::size_t at, std::uint16_t transaction, std::uint8_t unit,
                    std::size_t pdu_size);
  void on_write_done(std::size_t slot, std::uint32_t generation, Exception result);
  void on_forward_done(std::size_t slot, std::uint32_t generation, Exception result,
                       std::span<const std::uint8_t> reply);
  void unanswered(const PendingWrite& w, Exception result, bool settled_after);
  void process_completions();
  void flush();
  void on_flushed(const boost::system::error_code& ec);
  bool may_read() const;
  void arm_timer(net::TimePoint deadline);
  void on_timer(const boost::system::error_code& ec);
  std::optional<net::TimePoint> next_deadline() const;

  std::string who() const;

  std::shared_ptr<ServerState> state_;
  std::shared_ptr<ListenerState> listener_;
  boost::asio::ip::tcp::socket socket_;
  std::shared_ptr<boost::asio::ssl::context> tls_context_;  // kept alive for tls_
  std::optional<TlsStream> tls_;                            // TLS over socket_, once handshaken
  boost::asio::ip::tcp::endpoint peer_;
  Session session_;
  std::optional<std::string> role_;  // the TLS client certificate's role, if it has one
  std::string subject_;              // the TLS client certificate's subject
  net::Timer timer_;                 // on the server's clock
  net::TimePoint timer_deadline_ = net::TimePoint::max();

  // Receive buffer: fixed, large reads (many pipelined requests per read), never reallocated.
  std::vector<std::uint8_t> rx_;
  std::size_t rx_len_ = 0;
  // Replies being gathered for the next write, and the write in flight.
  std::vector<std::uint8_t> tx_pending_;
  std::vector<std::uint8_t> tx_inflight_;
  std::uint64_t flushing_reads_ = 0;  // FaultReads::served_count() when tx_inflight_ was filled

  std::vector<PendingWrite> writes_;
  std::size_t outstanding_ = 0;

  net::TimePoint last_request_;
  net::TimePoint started_;
  std::optional<net::TimePoint> partial_since_;  // a partial frame is buffered since then

  bool handshaking_ = false;  // TLS: no request is read before the handshake completed
  bool handshake_thread_has_socket_ = false;  // socket_ is shut down, not closed, until it is back
  bool denial_logged_ = false;  // a write beyond the access level is logged once per connection
  bool reading_ = false;
  bool writing_ = false;
  bool completions_posted_ = false;
  bool close_after_flush_ = false;  // a malformed header was seen
  bool input_done_ = false;         // the client half-closed: answer what it sent, then close
  bool closed_ = false;
};

}  // namespace drivegate::modbus
