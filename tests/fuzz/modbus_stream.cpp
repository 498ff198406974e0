#include "modbus_stream.h"

#include <algorithm>

#include "check.h"

namespace drivegate::fuzz {
namespace {

// Connection's per-connection pending-write cap (README: max_pending_writes, default 16).
constexpr std::size_t kMaxPendingWrites = 16;

}  // namespace

using modbus::Exception;
using modbus::MbapParse;

ModbusStream::ModbusStream(modbus::Backend& backend, std::function<bool()> settle)
    : settle_(std::move(settle)),
      dispatcher_(backend, {"drivegate", "fuzz", "0.0.0"}),
      slots_(std::make_shared<std::vector<Slot>>(kMaxPendingWrites)) {}

bool ModbusStream::receive(std::span<const std::uint8_t> segment) {
  if (closed_) return false;
  rx_.insert(rx_.end(), segment.begin(), segment.end());
  std::size_t offset = 0;
  while (offset < rx_.size()) {
    const auto rest = std::span<const std::uint8_t>(rx_).subspan(offset);
    const MbapParse parse = modbus::parse_mbap(rest);
    if (parse.status == MbapParse::Status::indeterminate) {
      // Only a header that could still be good waits: 6 + length bytes are not in yet.
      FUZZ_CHECK(rest.size() < 6 || rest.size() < 6 + std::size_t{static_cast<std::uint16_t>(
                                                          (rest[4] << 8) | rest[5])});
      break;
    }
    if (parse.status == MbapParse::Status::bad) {
      FUZZ_CHECK(parse.error);
      closed_ = true;
      rx_.clear();
      return false;
    }
    // Implementation Guide 3.1.3: the frame is exactly 6 + length bytes, PDU 1..253 bytes.
    FUZZ_CHECK(parse.consumed == 6 + std::size_t{parse.header.length});
    FUZZ_CHECK(parse.consumed <= rest.size());
    FUZZ_CHECK(!parse.pdu.empty() && parse.pdu.size() <= modbus::kMaxPduSize);
    FUZZ_CHECK(parse.pdu.data() == rest.data() + modbus::kMbapHeaderSize);
    FUZZ_CHECK(parse.header.unit == rest[6]);
    if (dispatcher_.answers_later(parse.header.unit, parse.pdu[0]) &&
        outstanding_ >= kMaxPendingWrites) {
      complete_writes();
      if (outstanding_ >= kMaxPendingWrites && !(settle_ && settle_())) break;
      complete_writes();
      if (outstanding_ >= kMaxPendingWrites) break;
    }
    // Copied: dispatch may not keep pointers into the receive buffer.
    const std::vector<std::uint8_t> pdu(parse.pdu.begin(), parse.pdu.end());
    dispatch(parse.header, pdu);
    offset += parse.consumed;
  }
  rx_.erase(rx_.begin(), rx_.begin() + static_cast<std::ptrdiff_t>(offset));
  return true;
}

void ModbusStream::dispatch(const modbus::MbapHeader& header, std::span<const std::uint8_t> pdu) {
  out_.fill(0xA5);
  modbus::Dispatcher::Result result;
  const bool forwarded = dispatcher_.forwards(header.unit);
  if (!dispatcher_.answers_later(header.unit, pdu[0])) {
    result = dispatcher_.handle(session_, header.unit, pdu, out_, {});
    FUZZ_CHECK(result.status == modbus::Dispatcher::Result::Status::reply);
  } else {
    auto& slots = *slots_;
    const auto it = std::find_if(slots.begin(), slots.end(), [](const Slot& s) { return !s.used; });
    FUZZ_CHECK(it != slots.end());
    const auto index = static_cast<std::size_t>(it - slots.begin());
    Slot& s = *it;
    s.used = true;
    s.done = false;
    s.transaction = header.transaction;
    s.unit = header.unit;
    s.request.assign(pdu.begin(), pdu.end());
    s.forwarded = forwarded;
    s.reply.clear();
    ++outstanding_;
    std::weak_ptr<std::vector<Slot>> weak = slots_;
    if (forwarded) {
      result = dispatcher_.forward(session_, header.unit, pdu, out_,
                                   [weak, index, generation = s.generation](
                                       Exception e, std::span<const std::uint8_t> reply) {
                                     const auto alive = weak.lock();
                                     if (!alive) return;
                                     Slot& w = (*alive)[index];
                                     FUZZ_CHECK(w.used && w.generation == generation && !w.done);
                                     w.done = true;
                                     w.result = e;
                                     w.reply.assign(reply.begin(), reply.end());
                                   });
    } else {
      result = dispatcher_.handle(session_, header.unit, pdu, out_,
                                  [weak, index, generation = s.generation](Exception e) {
                                    const auto alive = weak.lock();
                                    if (!alive)
                                      return;  // the connection is gone: the reply is dropped
                                    Slot& w = (*alive)[index];
                                    // Backend contract (backend.h): `done` is called exactly once.
                                    FUZZ_CHECK(w.used && w.generation == generation && !w.done);
                                    w.done = true;
                                    w.result = e;
                                  });
    }
    if (result.status == modbus::Dispatcher::Result::Status::reply) {
      // Refused before it started: `done` must never fire for it.
      s.used = false;
      ++s.generation;
      --outstanding_;
    }
  }
  if (result.status == modbus::Dispatcher::Result::Status::reply) {
    FUZZ_CHECK(result.size >= 2 && result.size <= modbus::kMaxPduSize);
    check_reply(pdu, std::span<const std::uint8_t>(out_.data(), result.size));
  }
}

void ModbusStream::complete_writes() {
  for (Slot& s : *slots_) {
    if (!s.used || !s.done) continue;
    out_.fill(0xA5);
    std::size_t size = 0;
    if (!s.forwarded) {
      size = dispatcher_.complete(session_, s.unit, s.request, s.result, out_);
    } else if (s.result == Exception::none) {
      // The device's reply as it came (the connection answers with it unchanged).
      FUZZ_CHECK(!s.reply.empty() && s.reply.size() <= modbus::kMaxPduSize);
      size = s.reply.size();
      std::copy(s.reply.begin(), s.reply.end(), out_.begin());
    } else {
      size = modbus::exception_pdu(s.request[0], s.result, out_);
    }
    if (s.forwarded && s.result == Exception::none) {
      ++replies_;  // the device's own PDU: whatever shape it has is what the client gets
    } else {
      FUZZ_CHECK(size >= 2 && size <= modbus::kMaxPduSize);
      check_reply(s.request, std::span<const std::uint8_t>(out_.data(), size));
    }
    s.used = false;
    ++s.generation;
    --outstanding_;
  }
}

// Application Protocol V1.1b3: a response carries the request's function code, or that code with
// bit 7 set followed by exactly one exception code (section 7); read replies carry a byte count
// that matches their size (6.1-6.4, 6.17).
void ModbusStream::check_reply(std::span<const std::uint8_t> request,
                               std::span<const std::uint8_t> reply) {
  ++replies_;
  const std::uint8_t fc = request[0];
  if (reply[0] == (fc | 0x80)) {
    FUZZ_CHECK(reply.size() == 2);
    FUZZ_CHECK(reply[1] != 0);
    return;
  }
  FUZZ_CHECK(reply[0] == fc);
  switch (fc) {
    case 0x01:
    case 0x02:
    case 0x03:
    case 0x04:
    case 0x17:
      FUZZ_CHECK(reply.size() == 2 + std::size_t{reply[1]});
      break;
    case 0x05:
    case 0x06:
      FUZZ_CHECK(reply.size() == 5 && std::equal(reply.begin(), reply.end(), request.begin()));
      break;
    case 0x0F:
    case 0x10:
      FUZZ_CHECK(reply.size() == 5 && std::equal(reply.begin(), reply.end(), request.begin()));
      break;
    default:
      break;
  }
}

}  // namespace drivegate::fuzz
