#include "slave_framer.h"

#include <algorithm>

namespace drivegate::modbus {

using modbus_serial::Framing;

namespace {

// Serial Line 2.5.1.1: the longest RTU frame is 256 bytes, the longest ASCII one 513 characters.
constexpr std::size_t kRtuMaxFrame = 256;
constexpr std::size_t kAsciiMaxFrame = 513;
// Above 19200 baud the timers are fixed (Serial Line 2.5.1.1, the note under figure 14).
constexpr unsigned kFixedAbove = 19200;
constexpr std::chrono::microseconds kFixedT15{750};
constexpr std::chrono::microseconds kFixedT35{1750};

FramerEvent::Kind kind_of(const std::error_code& e) {
  if (e == make_error_code(FrameError::bad_checksum)) return FramerEvent::Kind::bad_checksum;
  return FramerEvent::Kind::broken;
}

}  // namespace

LineTiming line_timing(unsigned baud, unsigned bits_per_char) {
  LineTiming t;
  if (baud == 0) return t;
  // One character: bits_per_char / baud seconds, in microseconds rounded down (a read is then
  // never taken to have begun before it did).
  const auto char_us = 1'000'000ULL * bits_per_char / baud;
  t.char_time = std::chrono::microseconds(char_us);
  if (baud > kFixedAbove) {
    t.t15 = kFixedT15;
    t.t35 = kFixedT35;
    return t;
  }
  // The timers on the character rounded up: a silence is never taken to be over early.
  const auto char_up = (1'000'000ULL * bits_per_char + baud - 1) / baud;
  t.t15 = std::chrono::microseconds((char_up * 3 + 1) / 2);
  t.t35 = std::chrono::microseconds((char_up * 7 + 1) / 2);
  return t;
}

SlaveFramer::SlaveFramer(Framing framing, Delimit delimit, LineTiming timing)
    : framing_(framing), delimit_(delimit), timing_(timing) {}

void SlaveFramer::push(FramerEvent::Kind kind, std::size_t bytes) {
  if (bytes == 0) return;
  FramerEvent e;
  e.kind = kind;
  e.bytes = bytes;
  events_.push_back(std::move(e));
}

// RTU on a line: the rest of what is buffered, and whatever comes before the next 3.5-character
// silence, is thrown away as one event of `kind`.
void SlaveFramer::skip_rest(FramerEvent::Kind kind) {
  if (!skipping_) {
    skipping_ = true;
    skip_kind_ = kind;
    skipped_ = 0;
  }
  skipped_ += rx_.size();
  rx_.clear();
  broken_ = false;
}

// What a silence (RTU) or a timeout (ASCII) that has come by `now` ends.
void SlaveFramer::settle(SerialClock::time_point now) {
  if (!last_ || delimit_ == Delimit::length) return;
  const auto quiet = now - *last_;
  if (framing_ == Framing::ascii) {
    if (quiet > timing_.ascii_timeout && !rx_.empty()) {
      push(FramerEvent::Kind::broken, rx_.size());
      rx_.clear();
    }
    return;
  }
  if (quiet < timing_.t35) return;
  after_request_ = false;
  if (skipping_) {
    // Fix: a run of more than the longest frame before a silence is the overrun the header
    // defines. take_frames() never saw one: the codec answers `bad` (CRC, bad length) long before
    // 256 bytes are buffered, so the run was skipped under that first kind instead.
    push(skipped_ > kRtuMaxFrame ? FramerEvent::Kind::overrun : skip_kind_, skipped_);
    skipping_ = false;
    skipped_ = 0;
  }
  // A frame that its length says is not all in, ended by the silence: cut short. Unless the port
  // may still be holding the rest back (LineTiming::latency).
  if (!rx_.empty() && quiet < std::max<SerialClock::duration>(timing_.t35, timing_.latency)) {
    return;
  }
  push(FramerEvent::Kind::broken, rx_.size());
  rx_.clear();
  broken_ = false;
}

void SlaveFramer::feed(ByteView bytes, SerialClock::time_point now) {
  if (bytes.empty()) return;
  // Where the read's first byte began on the wire: the silence before it ends there.
  auto began = now - timing_.char_time * static_cast<std::int64_t>(bytes.size());
  if (floor_ && began < *floor_) began = *floor_;
  read_floor_ = floor_;
  settle(began);
  const bool rtu_line = framing_ == Framing::rtu && delimit_ == Delimit::silence;
  if (rtu_line && last_ && !skipping_) {
    const auto gap = began - *last_;
    if (!rx_.empty() && gap > std::max<SerialClock::duration>(timing_.t15, timing_.latency)) {
      broken_ = true;
    }
    // settle() has seen no 3.5-character silence since a request, and no reply has gone out:
    // these come while the line should be silent. They are skipped when they come in the
    // request's own read, and so in a read of their own too. Once the host has replied
    // (replied()), the master may send at once: on a pseudo-terminal or a USB adapter its next
    // request can arrive within what looks like 3.5 characters of the last.
    if (rx_.empty() && after_request_ && gap < timing_.t35) broken_ = true;
  }
  if (delimit_ == Delimit::length && !rx_.empty() &&
      modbus_serial::decode_request(framing_, bytes).status == DecodeStatus::frame) {
    // Fix: what the header promises and nothing did: a read that starts with a good frame
    // resyncs the stream. The bytes an earlier read left, which can only be a frame's start, are
    // dropped instead of swallowing the good frame into a bad one.
    push(FramerEvent::Kind::broken, rx_.size());
    rx_.clear();
  }
  last_ = now;
  floor_ = now;
  if (rtu_line && skipping_) {
    skipped_ += bytes.size();
    return;
  }
  rx_.insert(rx_.end(), bytes.begin(), bytes.end());
  take_frames(now);
}

void SlaveFramer::take_frames(SerialClock::time_point now) {
  const bool rtu_line = framing_ == Framing::rtu && delimit_ == Delimit::silence;
  const std::size_t most = framing_ == Framing::rtu ? kRtuMaxFrame : kAsciiMaxFrame;
  if (rtu_line && broken_) {
    // Fix: a frame cut by a gap is discarded as broken at once, whatever its bytes would have
    // decoded to. It was only checked once a whole frame had decoded, so a cut frame whose bytes
    // then failed their CRC (a master resending after a pause) was counted a CRC error (FC 08
    // 0x0C), and one that grew past 256 bytes an overrun.
    skip_rest(FramerEvent::Kind::broken);
    return;
  }
  while (!rx_.empty()) {
    auto d = modbus_serial::decode_request(framing_, rx_);
    if (d.status == DecodeStatus::incomplete) {
      if (rx_.size() < most) return;
      // A guard: the codec answers a frame this long `bad_length` (below) before it could be
      // incomplete, but a frame that cannot end must never hold the buffer.
      if (rtu_line) {
        skip_rest(FramerEvent::Kind::overrun);
        return;
      }
      push(FramerEvent::Kind::overrun, rx_.size());
      rx_.clear();
      return;
    }
    if (d.status == DecodeStatus::bad) {
      auto kind = kind_of(d.error);
      // Fix: the codec answers a frame longer than the longest (ASCII: 513 characters without
      // CR LF) `bad_length` of that many bytes, so the `incomplete` branch above never got to
      // call it an overrun.
      if (d.error == make_error_code(FrameError::bad_length) && d.consumed >= most) {
        kind = FramerEvent::Kind::overrun;
      }
      if (rtu_line) {  // nothing on the line can be trusted until it falls silent
        skip_rest(kind);
        return;
      }
      const std::size_t n = std::min(std::max<std::size_t>(d.consumed, 1), rx_.size());
      push(kind, n);
      rx_.erase(rx_.begin(), rx_.begin() + static_cast<std::ptrdiff_t>(n));
      continue;
    }
    const std::size_t n = d.consumed;
    FramerEvent e;
    e.kind = FramerEvent::Kind::request;
    after_request_ = rtu_line;
    e.adu = std::move(d.frame);
    e.bytes = n;
    // On a line, the frame's last byte arrived before the bytes that follow it in this read; an
    // RTU reply waits 3.5 characters after it.
    const auto after = static_cast<std::int64_t>(rx_.size() - n);
    auto ended = delimit_ == Delimit::silence ? now - timing_.char_time * after : now;
    if (read_floor_ && ended < *read_floor_) ended = *read_floor_;
    e.reply_at = rtu_line ? ended + timing_.t35 : ended;
    events_.push_back(std::move(e));
    rx_.erase(rx_.begin(), rx_.begin() + static_cast<std::ptrdiff_t>(n));
    if (rtu_line && !rx_.empty()) {
      // More bytes before the silence that must follow a frame: not a request of ours.
      skip_rest(FramerEvent::Kind::broken);
      return;
    }
  }
}

std::optional<SerialClock::time_point> SlaveFramer::deadline() const {
  if (!last_ || delimit_ == Delimit::length) return std::nullopt;
  if (framing_ == Framing::ascii) {
    if (rx_.empty()) return std::nullopt;
    return *last_ + timing_.ascii_timeout + std::chrono::microseconds(1);
  }
  if (skipping_) return *last_ + timing_.t35;
  if (rx_.empty()) return std::nullopt;
  return *last_ + std::max<SerialClock::duration>(timing_.t35, timing_.latency);
}

void SlaveFramer::expire(SerialClock::time_point now) {
  if (!floor_ || *floor_ < now) floor_ = now;
  settle(now);
}

std::optional<FramerEvent> SlaveFramer::next() {
  if (taken_ >= events_.size()) {
    events_.clear();
    taken_ = 0;
    return std::nullopt;
  }
  return std::move(events_[taken_++]);
}

void SlaveFramer::reset() {
  rx_.clear();
  events_.clear();
  taken_ = 0;
  last_.reset();
  skipping_ = false;
  broken_ = false;
  after_request_ = false;
  skipped_ = 0;
}

}  // namespace drivegate::modbus
