// Fuzz target: what a Modbus master (or the noise on its line) sends a serial slave, through the
// SlaveFramer (daemon/modbus/slave_framer.h) as SlaveHost feeds it: reads of any size at any
// times, and expire() when a deadline comes. The same reads go to three framers: RTU on a line
// (Delimit::silence), RTU over TCP (Delimit::length) and ASCII on a line.
//
// Invariants, after every step: a request's PDU is 1..253 bytes and its address 0..247, it
// accounts for exactly the bytes its frame encodes to, and it may be answered t3.5 after the read
// that completed it (RTU on a line) or at once; expire() never yields a request; every event
// accounts for at least one byte, and never more bytes in all than were fed; a deadline, if any,
// is still to come. At the end, after an expire() far in the future: nothing is left buffered on a
// line (the events account for every byte fed, and there is no deadline); over TCP at most a
// frame's start (under 256 bytes) waits for the rest. And on a line, a read's bytes fed one at a
// time at the read's time give the very same events (RTU) or the same requests (ASCII, where
// noise is reported per read): when the line byte's bit 3 asks for it, as a frame the codec
// delimits by its CRC costs a rescan of every prefix for each byte fed alone.
//
// Input: a line byte (bits 0-1: 1200, 9600, 19200 or 115200 baud; bit 2: 10 or 11 bits a
// character; bit 3: the byte-by-byte comparison), then steps: an op byte and a 16-bit time gap
// (bits 14-15: unit of 1 us, 16 us, 1 ms or 64 us; bits 0-13: how many), then for a read (op bit 7
// clear) op & 0x7F bytes (0: 128); an op with bit 7 set is an expire() after the gap.
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "check.h"
#include "fuzz_input.h"
#include "slave_framer.h"

namespace {

using drivegate::Bytes;
using drivegate::ByteView;
using drivegate::modbus::Delimit;
using drivegate::modbus::FramerEvent;
using drivegate::modbus::LineTiming;
using drivegate::modbus::SerialClock;
using drivegate::modbus::SlaveFramer;
using Kind = FramerEvent::Kind;
namespace serial = drivegate::modbus_serial;
using std::chrono::microseconds;

constexpr std::size_t kRtuMaxFrame = 256;  // Serial Line 2.5.1.1

microseconds gap_of(std::uint16_t v) {
  const std::int64_t n = v & 0x3FFF;
  switch (v >> 14) {
    case 0:
      return microseconds(n);
    case 1:
      return microseconds(n * 16);
    case 2:
      return microseconds(n * 1000);
    default:
      return microseconds(n * 64);
  }
}

// One framer under test, and what it has said so far.
struct Probe {
  Probe(serial::Framing f, Delimit d, LineTiming t)
      : framing(f), delimit(d), timing(t), framer(f, d, t) {}

  void feed(ByteView bytes, SerialClock::time_point now) {
    framer.feed(bytes, now);
    fed += bytes.size();
    collect(now, true, bytes.size());
  }
  void expire(SerialClock::time_point now) {
    framer.expire(now);
    collect(now, false, 0);
  }

  void collect(SerialClock::time_point now, bool fed_now, std::size_t read) {
    while (auto e = framer.next()) {
      FUZZ_CHECK(e->bytes > 0);
      accounted += e->bytes;
      if (e->kind == Kind::request) {
        FUZZ_CHECK(fed_now);  // a request is taken when its last byte comes, never at a timeout
        FUZZ_CHECK(!e->adu.pdu.empty());
        FUZZ_CHECK(e->adu.pdu.size() <= serial::kMaxPdu);
        FUZZ_CHECK(e->adu.address <= serial::kMaxSlave);
        FUZZ_CHECK(serial::encode(framing, e->adu.address, e->adu.pdu).size() == e->bytes);
        const bool rtu_line = framing == serial::Framing::rtu && delimit == Delimit::silence;
        // The request ended at its last byte, within this read (on a line, a character for each
        // byte after it earlier); an RTU reply waits 3.5 characters from there.
        const auto wait = rtu_line ? SerialClock::duration(timing.t35) : SerialClock::duration{};
        const auto earliest = delimit == Delimit::silence
                                  ? now - timing.char_time * static_cast<std::int64_t>(read)
                                  : now;
        FUZZ_CHECK(e->reply_at <= now + wait);
        FUZZ_CHECK(e->reply_at >= earliest + wait);
      }
      events.push_back(std::move(*e));
    }
    FUZZ_CHECK(accounted <= fed);
    const auto d = framer.deadline();
    if (delimit == Delimit::length) FUZZ_CHECK(!d);
    if (d) FUZZ_CHECK(*d > now);
  }

  serial::Framing framing;
  Delimit delimit;
  LineTiming timing;
  SlaveFramer framer;
  std::size_t fed = 0;
  std::size_t accounted = 0;
  std::vector<FramerEvent> events;
};

bool same(const FramerEvent& a, const FramerEvent& b) {
  return a.kind == b.kind && a.bytes == b.bytes && a.adu.address == b.adu.address &&
         a.adu.pdu == b.adu.pdu && a.reply_at == b.reply_at;
}

std::vector<const FramerEvent*> requests(const std::vector<FramerEvent>& events) {
  std::vector<const FramerEvent*> out;
  for (const auto& e : events) {
    if (e.kind == Kind::request) out.push_back(&e);
  }
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  drivegate::fuzz::FuzzInput in(data, size);
  const std::uint8_t line = in.u8();
  static constexpr unsigned kBauds[] = {1200, 9600, 19200, 115200};
  const LineTiming timing =
      drivegate::modbus::line_timing(kBauds[line & 0x03], (line & 0x04) != 0 ? 11 : 10);

  Probe rtu(serial::Framing::rtu, Delimit::silence, timing);
  Probe rtu_bytes(serial::Framing::rtu, Delimit::silence, timing);  // each read byte by byte
  Probe tcp(serial::Framing::rtu, Delimit::length, timing);
  Probe ascii(serial::Framing::ascii, Delimit::silence, timing);
  Probe ascii_bytes(serial::Framing::ascii, Delimit::silence, timing);
  const bool by_byte = (line & 0x08) != 0;
  std::vector<Probe*> all = {&rtu, &tcp, &ascii};
  if (by_byte) {
    all.push_back(&rtu_bytes);
    all.push_back(&ascii_bytes);
  }

  auto now = SerialClock::time_point{} + std::chrono::hours(1);
  // The last read's (or expire's) time: none yet, as the framer knows none before the first read.
  auto previous = SerialClock::time_point{};
  while (!in.empty()) {
    const std::uint8_t op = in.u8();
    now += gap_of(in.u16());
    if ((op & 0x80) != 0) {
      for (Probe* p : all) p->expire(now);
      previous = now;
      continue;
    }
    const std::size_t n = (op & 0x7F) == 0 ? 128 : (op & 0x7F);
    const auto read = in.bytes(n);
    const ByteView bytes(read.data(), read.size());
    // The input ran out: no read (an empty feed() is no news, and settles nothing).
    if (bytes.empty()) break;
    rtu.feed(bytes, now);
    tcp.feed(bytes, now);
    ascii.feed(bytes, now);
    // Byte by byte, each when it arrived on the wire: a character apart, the last at `now` (and
    // never before the previous read).
    for (std::size_t i = 0; by_byte && i < bytes.size(); ++i) {
      const auto left = static_cast<std::int64_t>(bytes.size() - 1 - i);
      const auto at = std::max(now - timing.char_time * left, previous);
      rtu_bytes.feed(bytes.subspan(i, 1), at);
      ascii_bytes.feed(bytes.subspan(i, 1), at);
    }
    previous = now;
  }

  now += std::chrono::hours(24);
  for (Probe* p : all) p->expire(now);
  for (Probe* p : all) {
    if (p == &tcp) continue;
    FUZZ_CHECK(p->accounted == p->fed);
    FUZZ_CHECK(!p->framer.deadline());
  }
  FUZZ_CHECK(tcp.fed - tcp.accounted < kRtuMaxFrame);
  if (!by_byte) return 0;

  FUZZ_CHECK(rtu.events.size() == rtu_bytes.events.size());
  for (std::size_t i = 0; i < rtu.events.size(); ++i) {
    FUZZ_CHECK(same(rtu.events[i], rtu_bytes.events[i]));
  }
  const auto whole = requests(ascii.events);
  const auto split = requests(ascii_bytes.events);
  FUZZ_CHECK(whole.size() == split.size());
  for (std::size_t i = 0; i < whole.size(); ++i) FUZZ_CHECK(same(*whole[i], *split[i]));
  return 0;
}
