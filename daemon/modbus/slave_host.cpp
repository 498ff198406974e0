#include "slave_host.h"

#include <algorithm>
#include <boost/asio/post.hpp>

namespace drivegate::slave {

namespace asio = boost::asio;
using modbus::Exception;
using modbus::FramerEvent;

namespace {

constexpr std::uint8_t kDiagnostics = 0x08;  // Application Protocol 6.8: serial line only
constexpr std::uint8_t kReadWrite = 0x17;    // Application Protocol 6.17
constexpr std::size_t kMaxAccepted = 64;     // accepted writes whose result is still awaited
constexpr std::uint8_t kExceptionBit = 0x80;

}  // namespace

SlaveHost::SlaveHost(asio::io_context& io, net::Clock& clock, modbus::Backend& backend,
                     modbus::DeviceIdentity identity, modbus_serial::Framing framing,
                     modbus::Delimit delimit, modbus::LineTiming timing,
                     std::shared_ptr<const SlavePolicy> policy, LineCounters& counters,
                     std::shared_ptr<spdlog::logger> log, std::string name, Send send)
    : io_(io),
      clock_(clock),
      backend_(backend),
      dispatcher_(backend, std::move(identity)),
      framing_(framing),
      framer_(framing, delimit, timing),
      policy_(std::move(policy)),
      line_(counters),
      counters_(counters.counts),
      log_(std::move(log)),
      name_(std::move(name)),
      send_(std::move(send)),
      timer_(io.get_executor(), clock) {
  set_policy(policy_);
}

SlaveHost::~SlaveHost() = default;

void SlaveHost::set_policy(std::shared_ptr<const SlavePolicy> policy) {
  policy_ = std::move(policy);
  std::shared_ptr<FaultReads> reads =
      session_.fault_reads ? std::move(session_.fault_reads) : std::make_shared<FaultReads>();
  session_ = policy_->session;
  session_.fault_reads = std::move(reads);
}

void SlaveHost::stop() {
  stopped_ = true;
  reset();
}

void SlaveHost::reset() {
  framer_.reset();
  if (due_) ++counters_.server_no_response;  // the line went before it could be sent
  // Nor is a reply handed to the line known to have gone out: the reads before never count.
  session_.fault_reads->forget_in_flight();
  due_.reset();
  timer_.cancel();
  timer_armed_ = false;
  if (pending_) ++counters_.server_no_response;
  pending_.reset();  // its result, when it comes, finds no one (the audit trail has it)
}

void SlaveHost::receive(ByteView bytes) {
  if (stopped_ || bytes.empty()) return;
  // Anything the master sends after a request means it stopped waiting for that reply.
  if (pending_) superseded();
  if (due_) {  // the line was to stay silent until our reply: the master did not wait for it
    due_.reset();
    ++counters_.server_no_response;
    session_.fault_reads->unsent_dropped();
  }
  // Bytes that begin a new request: the master sent them after the replies gone out before,
  // which count as read from now (fault_reads.h).
  if (!framer_.partial()) session_.fault_reads->received();
  framer_.feed(bytes, clock_.now());
  drain();
}

void SlaveHost::superseded() {
  ++counters_.server_no_response;
  if (auto held = line_.late_log.admit(clock_.now())) {
    log_->warn(
        "modbus: {}: the master sent again before unit {} answered (function 0x{:02X}); "
        "that reply is dropped, never sent late (raise the master's response timeout, or "
        "write_reply = \"accepted\"){}",
        name_, pending_->unit, pending_->request.at(0), net::held_note(*held));
  }
  pending_.reset();
}

void SlaveHost::too_late(net::TimePoint would_leave) {
  ++counters_.server_no_response;
  if (auto held = line_.late_log.admit(clock_.now())) {
    const auto late = std::chrono::duration_cast<Millis>(would_leave - *pending_->give_up_at);
    log_->warn(
        "modbus: {}: unit {} answered (function 0x{:02X}) {} ms after the master's "
        "response timeout (reply_timeout_ms = {}); that reply is dropped, never sent late{}",
        name_, pending_->unit, pending_->request.at(0), late.count(),
        pending_->reply_timeout.count(), net::held_note(*held));
  }
  pending_.reset();
}

void SlaveHost::drain() {
  while (auto e = framer_.next()) serve(*e);
  arm();
}

void SlaveHost::serve(FramerEvent& e) {
  switch (e.kind) {
    case FramerEvent::Kind::bad_checksum:
      ++counters_.bus_messages;
      ++counters_.bus_comm_errors;
      return;
    case FramerEvent::Kind::overrun:
      ++counters_.bus_char_overruns;
      return;
    case FramerEvent::Kind::broken:
      ++counters_.broken_frames;
      return;
    case FramerEvent::Kind::request:
      break;
  }
  ++counters_.bus_messages;
  const auto& adu = e.adu;
  if (adu.address == modbus_serial::kBroadcast) {
    serve_broadcast(adu);
    return;
  }
  const std::uint8_t unit = adu.address;
  // Several slaves may share the line: only our own unit ids are answered (Serial Line 2.2).
  if (!backend_.serves(unit)) {
    ++counters_.other_units;
    return;
  }
  ++counters_.server_messages;
  if (pending_) {  // a request while one is in progress: receive() already gave that one up
    pending_.reset();
  }
  const std::span<const std::uint8_t> pdu = adu.pdu;
  const Session& session = session_;
  if (pdu[0] == kDiagnostics && !dispatcher_.forwards(unit)) {
    const std::size_t n = modbus::diagnostics(pdu, line_.counts, line_.cleared, out_);
    reply(unit, std::span(out_).first(n), e.reply_at);
    return;
  }
  if (!dispatcher_.answers_later(unit, pdu[0])) {
    const auto r = dispatcher_.handle(session, unit, pdu, out_, {});
    reply(unit, std::span(out_).first(r.size), e.reply_at);
    return;
  }
  Pending p;
  p.generation = ++generation_;
  p.unit = unit;
  p.request.assign(pdu.begin(), pdu.end());
  p.forwarded = dispatcher_.forwards(unit);
  p.reply_at = e.reply_at;
  p.reply_timeout = policy_->reply_timeout;
  if (p.reply_timeout > Millis(0)) p.give_up_at = e.reply_at + p.reply_timeout;
  pending_ = std::move(p);
  const auto generation = generation_;
  // `done` may fire inside handle(): on_done defers to the event loop.
  std::weak_ptr<SlaveHost> weak = weak_from_this();
  modbus::Dispatcher::Result r;
  if (pending_->forwarded) {
    r = dispatcher_.forward(session, unit, pdu, out_,
                            [weak, generation](Exception x, std::span<const std::uint8_t> reply) {
                              if (auto self = weak.lock()) self->on_done(generation, x, reply);
                            });
  } else {
    r = dispatcher_.handle(session, unit, pdu, out_, [weak, generation](Exception x) {
      if (auto self = weak.lock()) self->on_done(generation, x, {});
    });
  }
  if (r.denied) {
    if (auto held = line_.denied_log.admit(clock_.now())) {
      log_->warn(
          "modbus: {}: write (function 0x{:02X}, unit {}) beyond its access level \"{}\": "
          "refused with exception 01{}",
          name_, pdu[0], unit, to_string(session.access), net::held_note(*held));
    }
  }
  if (r.status == modbus::Dispatcher::Result::Status::reply) {  // refused before it started
    pending_.reset();
    reply(unit, std::span(out_).first(r.size), e.reply_at);
    return;
  }
  if (policy_->write_reply == WriteReply::accepted && !pending_->forwarded) {
    // Validated and queued: the normal response now (for 0x17, the registers as they are). The
    // write's own result, when it comes, is only checked for a failure to tell of.
    const std::size_t n = dispatcher_.complete(session, unit, pdu, Exception::none, out_);
    if (accepted_.size() >= kMaxAccepted) accepted_.erase(accepted_.begin());  // oldest
    accepted_.emplace(pending_->generation, Accepted{unit, pdu[0]});
    pending_.reset();
    reply(unit, std::span(out_).first(n), e.reply_at);
  }
}

// Address 0 (Serial Line 2.1): a write to every slave, never answered. Reads make no sense there
// and are ignored. A write moves motors on every drive at once, so it is applied only where the
// listener says broadcast = true; otherwise it is refused, counted, logged and told to the audit
// trail.
void SlaveHost::serve_broadcast(const modbus_serial::Adu& adu) {
  ++counters_.broadcasts;
  ++counters_.server_messages;
  ++counters_.server_no_response;
  const std::span<const std::uint8_t> pdu = adu.pdu;
  // Writes only: 0x17 reads too, and a broadcast has nobody to answer (Serial Line 2.1).
  if (!modbus::may_write(pdu[0]) || pdu[0] == kReadWrite) return;
  const Session& session = session_;
  if (!policy_->broadcast) {
    ++counters_.broadcasts_refused;
    backend_.refused_broadcast(session, pdu);
    if (auto held = line_.broadcast_log.admit(clock_.now())) {
      log_->warn(
          "modbus: {}: broadcast write (function 0x{:02X}) refused: not applied to any "
          "drive (the listener has broadcast = false){}",
          name_, pdu[0], net::held_note(*held));
    }
    return;
  }
  // Every unit here that is not a pass-through window (whose slave hears its own line's
  // broadcasts, not ours) gets the write through the one validated path; what each says is in
  // the audit trail, since nobody is answered.
  for (unsigned u = 1; u <= modbus_serial::kMaxSlave; ++u) {
    const auto unit = static_cast<std::uint8_t>(u);
    if (!backend_.serves(unit) || dispatcher_.forwards(unit)) continue;
    dispatcher_.handle(session, unit, pdu, broadcast_out_, [](Exception) {});
  }
}

void SlaveHost::on_done(std::uint32_t generation, Exception result,
                        std::span<const std::uint8_t> forwarded_reply) {
  // Deferred: the dispatcher's scratch may still hold the write that called this.
  Bytes reply_copy(forwarded_reply.begin(), forwarded_reply.end());
  asio::post(io_,
             [weak = weak_from_this(), generation, result, reply_copy = std::move(reply_copy)] {
               auto self = weak.lock();
               if (!self || self->stopped_) return;
               self->settle(generation, result, reply_copy);
               if (self->settled_) self->settled_();
             });
}

void SlaveHost::settle(std::uint32_t generation, Exception result, const Bytes& forwarded_reply) {
  if (const auto a = accepted_.find(generation); a != accepted_.end()) {
    const Accepted w = a->second;
    accepted_.erase(a);
    if (result != Exception::none) {  // write_reply = accepted: the master was told ok
      ++counters_.write_timeouts;
      if (auto held = line_.accepted_log.admit(clock_.now())) {
        log_->warn(
            "modbus: {}: write to unit {} (function 0x{:02X}) answered as "
            "accepted, then not applied: {}{}",
            name_, w.unit, w.function, modbus::to_string(result), net::held_note(*held));
      }
    }
    return;
  }
  auto& p = pending_;
  if (!p || p->generation != generation) return;  // given up on: never answered late
  if (const auto leaves = std::max(clock_.now(), p->reply_at);
      p->give_up_at && leaves > *p->give_up_at) {
    too_late(leaves);
    return;
  }
  std::size_t n = 0;
  if (p->forwarded && result == Exception::none) {
    n = std::min(forwarded_reply.size(), out_.size());
    std::copy_n(forwarded_reply.begin(), n, out_.begin());
  } else if (p->forwarded) {
    n = modbus::exception_pdu(p->request.at(0), result, out_);
  } else {
    n = dispatcher_.complete(session_, p->unit, p->request, result, out_);
  }
  const auto unit = p->unit;
  const auto at = p->reply_at;
  pending_.reset();
  reply(unit, std::span(out_).first(n), at);
}

void SlaveHost::count_reply(std::span<const std::uint8_t> pdu) {
  if (pdu.size() < 2 || (pdu[0] & kExceptionBit) == 0) return;
  ++counters_.bus_exception_errors;
  if (pdu[1] == static_cast<std::uint8_t>(Exception::server_device_busy)) ++counters_.server_busy;
}

void SlaveHost::reply(std::uint8_t unit, std::span<const std::uint8_t> pdu, net::TimePoint at) {
  if (pdu.empty()) return;
  Bytes frame = modbus_serial::encode(framing_, unit, pdu);
  if (clock_.now() >= at) {
    put(std::move(frame));
    return;
  }
  due_.emplace(at, std::move(frame));
  arm();
}

// Onto the line, counted as what it is (an exception reply: FC 08 0x0D, 0x11) when it goes.
void SlaveHost::put(Bytes frame) {
  const std::size_t head = framing_ == modbus_serial::Framing::rtu ? 1 : 0;
  if (framing_ == modbus_serial::Framing::rtu && frame.size() >= 3) {
    count_reply(std::span(frame).subspan(head, 2));
  } else if (auto d = modbus_serial::decode_reply(framing_, frame);
             d.status == DecodeStatus::frame && d.frame.pdu.size() >= 2) {
    count_reply(std::span(d.frame.pdu).first(2));
  }
  framer_.replied();
  send_(std::move(frame));
  session_.fault_reads->all_sent();  // one request at a time: this is its reply
}

void SlaveHost::arm() {
  std::optional<net::TimePoint> at = framer_.deadline();
  if (due_ && (!at || due_->first < *at)) at = due_->first;
  if (!at) {
    if (timer_armed_) timer_.cancel();
    timer_armed_ = false;
    return;
  }
  if (timer_armed_ && timer_at_ == *at) return;
  timer_at_ = *at;
  timer_armed_ = true;
  timer_.expires_at(*at);
  timer_.async_wait([weak = weak_from_this()](const boost::system::error_code& ec) {
    if (auto self = weak.lock()) self->on_timer(ec);
  });
}

void SlaveHost::on_timer(const boost::system::error_code& ec) {
  if (ec || stopped_) return;
  timer_armed_ = false;
  timer_at_ = net::TimePoint::max();
  const auto now = clock_.now();
  if (due_ && now >= due_->first) {
    Bytes frame = std::move(due_->second);
    due_.reset();
    put(std::move(frame));
    if (settled_ && !busy()) settled_();
  }
  framer_.expire(now);
  drain();
}

}  // namespace drivegate::slave
