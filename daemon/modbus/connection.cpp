#include "connection.h"

#include <openssl/ssl.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <boost/asio/post.hpp>
#include <boost/asio/ssl/error.hpp>
#include <boost/asio/write.hpp>
#include <cstring>

namespace drivegate::modbus {
namespace {

namespace asio = boost::asio;

// One read takes up to 16 KiB: dozens of pipelined requests in one system call.
constexpr std::size_t kReceiveBuffer = 16 * 1024;
// Replies not yet taken by a slow client: past this the connection stops reading until they are.
constexpr std::size_t kMaxReplyBacklog = 64 * 1024;
// Longest TLS handshake when frame_timeout is 0 (off): a client that opens a TLS listener and
// never finishes the handshake holds a client slot, so it is never unbounded.
constexpr std::chrono::milliseconds kHandshakeLimit{10'000};

// A TLS handshake must finish within frame_timeout (a request must arrive whole within it too).
std::chrono::milliseconds handshake_limit(const ServerOptions& o) {
  return o.frame_timeout.count() > 0 ? o.frame_timeout : kHandshakeLimit;
}

}  // namespace

Connection::Connection(std::shared_ptr<ServerState> state, std::shared_ptr<ListenerState> listener,
                       asio::ip::tcp::socket socket)
    : state_(std::move(state)),
      listener_(std::move(listener)),
      socket_(std::move(socket)),
      timer_(state_->io.get_executor(), state_->clock),
      rx_(kReceiveBuffer),
      writes_(std::max<std::size_t>(1, state_->options.max_pending_writes)) {
  tx_pending_.reserve(kReceiveBuffer);
  tx_inflight_.reserve(kReceiveBuffer);
  // What this client reads of the drives' faults, for the runs it asks (fault_reads.h).
  session_.fault_reads = std::make_shared<FaultReads>();
}

Connection::~Connection() {
  close();
}

std::string Connection::who() const {
  return "client " + peer_.address().to_string() + ":" + std::to_string(peer_.port()) + " on " +
         listener_->options.name();
}

void Connection::start() {
  boost::system::error_code ec;
  socket_.set_option(asio::ip::tcp::no_delay(true), ec);  // replies leave at once
  peer_ = socket_.remote_endpoint(ec);
  state_->live.insert(this);  // its listener's acceptor counted it in
  state_->log->debug("modbus: {} connected", who());
  started_ = last_request_ = state_->clock.now();
  if (listener_->tls) {
    tls_context_ = listener_->tls;
    handshaking_ = true;
    if (auto deadline = next_deadline()) arm_timer(*deadline);
    socket_.native_non_blocking(true, ec);
    handshake_thread_has_socket_ = true;
    state_->handshaker->start(socket_.native_handle(), tls_context_,
                              [self = shared_from_this()](HandshakeResult result) {
                                self->on_handshake(std::move(result));
                              });
    return;
  }
  apply_policy();
  if (auto deadline = next_deadline()) arm_timer(*deadline);
  read();
}

void Connection::on_handshake(HandshakeResult result) {
  handshake_thread_has_socket_ = false;
  if (closed_) {
    boost::system::error_code ec;
    socket_.close(ec);  // close() only shut it down: the handshake thread had it
    return;
  }
  handshaking_ = false;
  SSL* ssl = result.ssl.get();
  if (result.error || ssl == nullptr) {
    ++listener_->stats.tls_handshake_failures;
    // OpenSSL's reason ("certificate verify failed") says little; the verification result
    // says which check failed, and the subject whose certificate it was.
    const long verify = ssl != nullptr ? SSL_get_verify_result(ssl) : X509_V_OK;
    X509* cert = ssl != nullptr ? SSL_get0_peer_certificate(ssl) : nullptr;
    if (const auto held = listener_->handshake_log.admit(state_->clock.now())) {
      state_->log->warn(
          "modbus: {}: TLS handshake failed: {}{}{}; closing{}", who(), result.error.message(),
          verify != X509_V_OK ? std::string(" (") + X509_verify_cert_error_string(verify) + ")"
                              : std::string(),
          cert != nullptr ? ", certificate \"" + certificate_subject(cert) + "\"" : std::string(),
          net::held_note(*held));
    }
    close();
    return;
  }
  tls_.emplace(socket_, std::move(result.ssl));
  X509* cert = SSL_get0_peer_certificate(tls_->native_handle());
  role_ = certificate_role(cert);
  subject_ = certificate_subject(cert);
  apply_policy();
  state_->log->info("modbus: {}: {}, certificate \"{}\", role {}: access {}", who(),
                    SSL_get_version(tls_->native_handle()), subject_,
                    role_ ? "\"" + *role_ + "\"" : std::string("(none)"),
                    to_string(session_.access));
  last_request_ = state_->clock.now();
  if (auto deadline = next_deadline(); deadline && *deadline < timer_deadline_) {
    arm_timer(*deadline);
  }
  read();
}

// The session from the listener's policy: its word order, and its access level, or on TLS the
// level of the certificate's role when the roles table names it; and who the client is, for the
// audit trail.
void Connection::apply_policy() {
  const ListenerPolicy& p = listener_->options.policy;
  session_.word_order = p.word_order;
  session_.access = p.access;
  session_.source = Source{
      .kind = p.tls ? SourceKind::modbus_tls : SourceKind::modbus,
      .listener = listener_->options.name(),
      .client = peer_.address().to_string() + ":" + std::to_string(peer_.port()),
      .subject = subject_,
      .role = role_.value_or(""),
  };
  if (p.tls && role_) {
    if (const auto it = p.tls->roles.find(*role_); it != p.tls->roles.end()) {
      session_.access = it->second;
    }
  }
}

void Connection::policy_changed() {
  if (closed_) return;
  if (!net::allowed(listener_->options.policy.allow, peer_.address())) {
    state_->log->info("modbus: {}: no longer in the listener's allow list; closing", who());
    close();
    return;
  }
  const Session before = session_;
  if (!handshaking_) apply_policy();
  if (session_.access != before.access) {
    state_->log->info("modbus: {}: access {} -> {}", who(), to_string(before.access),
                      to_string(session_.access));
    denial_logged_ = false;
  }
}

std::optional<net::TimePoint> Connection::evictable_since() const {
  if (closed_ || handshaking_ || session_.access != AccessLevel::read || outstanding_ != 0 ||
      partial_since_) {
    return std::nullopt;
  }
  return last_request_;
}

void Connection::evict() {
  ++listener_->stats.connections_evicted;
  close();
}

void Connection::close() {
  if (closed_) return;
  closed_ = true;
  boost::system::error_code ec;
  socket_.shutdown(asio::ip::tcp::socket::shutdown_both, ec);
  // The handshake thread still reads and writes the descriptor: the shutdown ends its handshake
  // at once, and on_handshake closes the socket when the thread has handed it back.
  if (!handshake_thread_has_socket_) socket_.close(ec);
  timer_.cancel();
  // A write already settled but not yet answered cannot be told now; one still with its device
  // is counted when it settles (on_write_done).
  for (auto& w : writes_) {
    if (!w.used || !w.done) continue;
    unanswered(w, w.result, false);
    w.used = false;
    ++w.generation;
  }
  outstanding_ = 0;
  if (state_->live.erase(this) != 0) listener_->acceptor->left();
}

bool Connection::may_read() const {
  return !closed_ && !handshaking_ && !reading_ && !close_after_flush_ && !input_done_ &&
         outstanding_ < writes_.size() && tx_pending_.size() < kMaxReplyBacklog &&
         rx_len_ < rx_.size();
}

void Connection::read() {
  if (!may_read()) return;
  reading_ = true;
  const auto into = asio::buffer(rx_.data() + rx_len_, rx_.size() - rx_len_);
  auto done = [self = shared_from_this()](const boost::system::error_code& ec, std::size_t n) {
    self->on_read(ec, n);
  };
  if (tls_) {
    tls_->async_read_some(into, std::move(done));
  } else {
    socket_.async_read_some(into, std::move(done));
  }
}

void Connection::on_read(const boost::system::error_code& ec, std::size_t n) {
  reading_ = false;
  if (closed_) return;
  // The client is done sending (a TLS client may close without close_notify: the same): carry
  // out and answer everything it asked, writes still with their devices included, then close.
  if (ec == asio::error::eof || ec == asio::ssl::error::stream_truncated) {
    input_done_ = true;
    flush();
    return;
  }
  if (ec) {
    if (ec != asio::error::operation_aborted) {
      state_->log->debug("modbus: {}: {}", who(), ec.message());
    }
    close();
    return;
  }
  // Bytes that begin a new request: the client sent them after the replies gone out before,
  // which count as read from now (fault_reads.h). Bytes that finish a request already begun (or
  // follow one held at the write cap) were sent before.
  if (rx_len_ == 0) session_.fault_reads->received();
  rx_len_ += n;
  listener_->stats.bytes_received += n;
  process_input(state_->clock.now());
  flush();
  read();
}

// Dispatches every complete request in the receive buffer, stopping at a partial frame, at a
// malformed header, or at a write when the connection has as many writes outstanding as it may.
void Connection::process_input(net::TimePoint now) {
  std::size_t offset = 0;
  bool partial = false;
  while (offset < rx_len_) {
    const auto parse =
        parse_mbap(std::span<const std::uint8_t>(rx_.data() + offset, rx_len_ - offset));
    if (parse.status == MbapParse::Status::indeterminate) {
      partial = true;
      break;
    }
    if (parse.status == MbapParse::Status::bad) {
      ++listener_->stats.malformed;
      if (const auto held = state_->malformed_log.admit(now)) {
        state_->log->warn("modbus: {}: {}, closing the connection{}", who(), parse.error.message(),
                          net::held_note(*held));
      }
      close_after_flush_ = true;
      rx_len_ = 0;
      partial_since_.reset();
      return;
    }
    // At the cap a write (or a forwarded request) waits in the buffer, and so does everything
    // after it, to keep the order in which requests reach the backend.
    if (outstanding_ >= writes_.size() &&
        state_->dispatcher.answers_later(parse.header.unit, parse.pdu[0])) {
      break;
    }
    last_request_ = now;
    dispatch(parse.header, parse.pdu);
    offset += parse.consumed;
    if (closed_) return;
  }
  if (offset > 0) {
    std::memmove(rx_.data(), rx_.data() + offset, rx_len_ - offset);
    rx_len_ -= offset;
  }
  if (!partial) {
    partial_since_.reset();
  } else if (offset > 0 || !partial_since_) {
    partial_since_ = now;  // a new partial frame: its clock starts now
    if (state_->options.frame_timeout.count() > 0) {
      const auto deadline = now + state_->options.frame_timeout;
      if (deadline < timer_deadline_) arm_timer(deadline);
    }
  }
}

std::span<std::uint8_t> Connection::reserve_reply() {
  const std::size_t at = tx_pending_.size();
  tx_pending_.resize(at + kMaxAduSize);
  return {tx_pending_.data() + at + kMbapHeaderSize, kMaxPduSize};
}

void Connection::commit_reply(std::size_t at, std::uint16_t transaction, std::uint8_t unit,
                              std::size_t pdu_size) {
  put_mbap(std::span<std::uint8_t>(tx_pending_.data() + at, kMbapHeaderSize), transaction, unit,
           pdu_size);
  tx_pending_.resize(at + kMbapHeaderSize + pdu_size);
  ++listener_->stats.responses;
  const std::uint8_t fc = tx_pending_[at + kMbapHeaderSize];
  if ((fc & 0x80) != 0) {
    const std::uint8_t code = tx_pending_[at + kMbapHeaderSize + 1];
    ++listener_->stats.exceptions[code < listener_->stats.exceptions.size() ? code : 0];
  }
}

void Connection::dispatch(const MbapHeader& header, std::span<const std::uint8_t> pdu) {
  ++listener_->stats.requests;
  const std::size_t at = tx_pending_.size();
  const auto out = reserve_reply();
  Dispatcher::Result result;
  // A pass-through unit answers every request later, with its device's reply.
  const bool forwarded = state_->dispatcher.forwards(header.unit);
  if (!state_->dispatcher.answers_later(header.unit, pdu[0])) {
    result = state_->dispatcher.handle(session_, header.unit, pdu, out, {});
  } else {
    // A free slot exists: process_input stops at the cap. It is filled before the backend sees
    // the write, since `done` may fire before write() returns.
    const auto slot = static_cast<std::size_t>(
        std::find_if(writes_.begin(), writes_.end(), [](const auto& w) { return !w.used; }) -
        writes_.begin());
    PendingWrite& w = writes_[slot];
    w.used = true;
    w.done = false;
    w.transaction = header.transaction;
    w.unit = header.unit;
    w.size = static_cast<std::uint8_t>(pdu.size());
    w.forwarded = forwarded;
    w.reply_size = 0;
    std::copy(pdu.begin(), pdu.end(), w.request.begin());
    ++outstanding_;
    if (forwarded) {
      result =
          state_->dispatcher.forward(session_, header.unit, pdu, out,
                                     [self = shared_from_this(), slot, generation = w.generation](
                                         Exception e, std::span<const std::uint8_t> reply) {
                                       self->on_forward_done(slot, generation, e, reply);
                                     });
    } else {
      result =
          state_->dispatcher.handle(session_, header.unit, pdu, out,
                                    [self = shared_from_this(), slot, generation = w.generation](
                                        Exception e) { self->on_write_done(slot, generation, e); });
    }
    if (result.status == Dispatcher::Result::Status::reply) {  // refused before it started
      w.used = false;
      ++w.generation;
      --outstanding_;
    }
  }
  auto& by_function = listener_->stats.by_function;
  ++by_function[pdu[0] < by_function.size() ? pdu[0] : 0];
  if (result.denied) {
    ++listener_->stats.writes_denied;
    // Once per connection (a PLC retrying), and paced per listener (a client connecting anew
    // for each write): neither floods the journal. The audit trail has each (folded in a flood).
    if (!denial_logged_) {
      denial_logged_ = true;
      if (const auto held = listener_->denied_log.admit(state_->clock.now())) {
        state_->log->warn(
            "modbus: {}: write (function 0x{:02X}, unit {}) beyond its access level \"{}\": "
            "refused with exception 01 (further refusals on this connection are counted "
            "only){}",
            who(), pdu[0], header.unit, to_string(session_.access), net::held_note(*held));
      }
    }
  }
  if (result.status == Dispatcher::Result::Status::reply) {
    commit_reply(at, header.transaction, header.unit, result.size);
  } else {
    tx_pending_.resize(at);
  }
}

// Never does any work itself: the backend may call it from inside Backend::write (of this or
// another connection), while the shared dispatcher's scratch still holds that write's values.
void Connection::on_write_done(std::size_t slot, std::uint32_t generation, Exception result) {
  if (slot >= writes_.size()) return;
  PendingWrite& w = writes_[slot];
  if (!w.used || w.generation != generation || w.done) return;
  if (closed_) {
    unanswered(w, result, true);
    w.used = false;
    ++w.generation;
    return;
  }
  w.done = true;
  w.result = result;
  if (completions_posted_) return;
  completions_posted_ = true;
  asio::post(state_->io, [self = shared_from_this()] { self->process_completions(); });
}

// The device's reply is kept in the slot until process_completions() answers with it.
void Connection::on_forward_done(std::size_t slot, std::uint32_t generation, Exception result,
                                 std::span<const std::uint8_t> reply) {
  if (slot >= writes_.size()) return;
  PendingWrite& w = writes_[slot];
  if (!w.used || w.generation != generation || w.done) return;
  // A reply PDU is 1..253 bytes (the adapter's codec holds it to that); anything else is no reply.
  if (result == Exception::none && (reply.empty() || reply.size() > w.reply.size())) {
    result = Exception::gateway_target_failed;
  }
  if (result == Exception::none) {
    std::copy(reply.begin(), reply.end(), w.reply.begin());
    w.reply_size = static_cast<std::uint8_t>(reply.size());
  }
  on_write_done(slot, generation, result);
}

// The client that sent this write can no longer be told how it went: counted and logged, with
// what became of it, so that a write applied for nobody is never silent.
void Connection::unanswered(const PendingWrite& w, Exception result, bool settled_after) {
  ++listener_->stats.writes_unanswered;
  if (const auto held = state_->unanswered_log.admit(state_->clock.now())) {
    state_->log->warn(
        "modbus: {}: write (function 0x{:02X}, unit {}) {} {} the client closed: it was not told"
        "{}",
        who(), w.request[0], w.unit,
        result == Exception::none
            ? "took effect"
            : fmt::format("failed (exception 0x{:02X})", static_cast<unsigned>(result)),
        settled_after ? "after" : "as", net::held_note(*held));
  }
}

void Connection::process_completions() {
  completions_posted_ = false;
  if (closed_) return;
  for (auto& w : writes_) {
    if (!w.used || !w.done) continue;
    const std::size_t at = tx_pending_.size();
    const auto out = reserve_reply();
    std::size_t size = 0;
    if (!w.forwarded) {
      size = state_->dispatcher.complete(
          session_, w.unit, std::span<const std::uint8_t>(w.request.data(), w.size), w.result, out);
    } else if (w.result == Exception::none) {
      size = w.reply_size;
      std::copy_n(w.reply.begin(), size, out.begin());
    } else {
      size = exception_pdu(w.request[0], w.result, out);
    }
    commit_reply(at, w.transaction, w.unit, size);
    w.used = false;
    ++w.generation;
    --outstanding_;
  }
  // Requests held back at the cap may go now.
  if (!close_after_flush_ && rx_len_ > 0) process_input(state_->clock.now());
  flush();
  read();
}

void Connection::flush() {
  if (closed_ || writing_) return;
  if (tx_pending_.empty()) {
    // Half-closed: once no write is with its device, whatever is left in the buffer is a frame
    // the client will never finish.
    if (close_after_flush_ || (input_done_ && outstanding_ == 0)) close();
    return;
  }
  std::swap(tx_pending_, tx_inflight_);
  tx_pending_.clear();
  writing_ = true;
  flushing_reads_ = session_.fault_reads->served_count();  // their replies are in this batch
  auto done = [self = shared_from_this()](const boost::system::error_code& ec, std::size_t) {
    self->on_flushed(ec);
  };
  if (tls_) {
    tls_->async_write(asio::buffer(tx_inflight_), std::move(done));
  } else {
    asio::async_write(socket_, asio::buffer(tx_inflight_), std::move(done));
  }
}

void Connection::on_flushed(const boost::system::error_code& ec) {
  writing_ = false;
  if (closed_) return;
  if (ec) {
    close();
    return;
  }
  tx_inflight_.clear();
  session_.fault_reads->sent(flushing_reads_);
  flush();
  read();
}

std::optional<net::TimePoint> Connection::next_deadline() const {
  std::optional<net::TimePoint> deadline;
  const auto& o = state_->options;
  if (handshaking_) return started_ + handshake_limit(o);
  if (o.idle_timeout.count() > 0) deadline = last_request_ + o.idle_timeout;
  if (partial_since_ && o.frame_timeout.count() > 0) {
    const auto frame = *partial_since_ + o.frame_timeout;
    if (!deadline || frame < *deadline) deadline = frame;
  }
  return deadline;
}

void Connection::limits_changed() {
  if (closed_) return;
  // A deadline already past (a client silent for longer than the new idle_timeout) arms the timer
  // for now: its handler runs in a later turn of the loop and closes the connection there.
  if (auto deadline = next_deadline(); deadline && *deadline < timer_deadline_) {
    arm_timer(*deadline);
  }
}

// One timer per connection, moved only when a deadline comes earlier than the armed one; when it
// fires it checks what is really due (requests push the idle deadline without touching it).
void Connection::arm_timer(net::TimePoint deadline) {
  timer_deadline_ = deadline;
  timer_.expires_at(deadline);
  timer_.async_wait(
      [self = shared_from_this()](const boost::system::error_code& ec) { self->on_timer(ec); });
}

void Connection::on_timer(const boost::system::error_code& ec) {
  if (ec == asio::error::operation_aborted || closed_) return;
  timer_deadline_ = net::TimePoint::max();
  const auto now = state_->clock.now();
  const auto& o = state_->options;
  if (handshaking_ && now - started_ >= handshake_limit(o)) {
    ++listener_->stats.tls_handshake_failures;
    if (const auto held = listener_->handshake_log.admit(now)) {
      state_->log->warn("modbus: {}: TLS handshake not finished in {} ms; closing{}", who(),
                        handshake_limit(o).count(), net::held_note(*held));
    }
    close();
    return;
  }
  if (partial_since_ && o.frame_timeout.count() > 0 && now - *partial_since_ >= o.frame_timeout) {
    ++listener_->stats.frame_timeouts;
    if (const auto held = state_->frame_timeout_log.admit(now)) {
      state_->log->info("modbus: {}: partial frame for {} ms, closing{}", who(),
                        o.frame_timeout.count(), net::held_note(*held));
    }
    close();
    return;
  }
  if (o.idle_timeout.count() > 0 && outstanding_ == 0 && now - last_request_ >= o.idle_timeout) {
    ++listener_->stats.idle_timeouts;
    state_->log->info("modbus: {}: no request for {} ms, closing", who(), o.idle_timeout.count());
    close();
    return;
  }
  auto deadline = next_deadline();
  if (deadline && *deadline <= now) deadline = now + o.idle_timeout;  // waiting on writes
  if (deadline) arm_timer(*deadline);
}

}  // namespace drivegate::modbus
