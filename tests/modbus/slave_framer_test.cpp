// The receive side of a Modbus serial-line slave (slave_framer.h), on injected time.
//
// Documents: "MODBUS over Serial Line Specification and Implementation Guide V1.02" ("Serial
// Line") for the framing: RTU 2.5.1 / 2.5.1.1 (3.5-character silence between frames, a gap of
// more than 1.5 characters inside one discards it, 750 us / 1.75 ms above 19200 baud), the CRC
// 6.2.2, ASCII 2.5.2.1 (':' .. CR LF, 1 s inter-character timeout) and the LRC 6.2.1; and "MODBUS
// Application Protocol Specification V1.1b3" ("Application Protocol") for the request PDUs of
// the golden vectors, its own examples (section cited on each). The CRC / LRC bytes written out
// below were computed apart from the code under test (a reference CRC-16/MODBUS in Python), and
// 11 03 00 6B 00 03 76 87 / ":1103006B00037E" are the Modicon reference guide's (PI-MBUS-300)
// well-known examples of the same request.
//
// Every test ends with the bytes accounting the header promises: once everything has settled,
// the events' `bytes` add up to the bytes fed.
#include "slave_framer.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "drivegate/crc.h"

namespace drivegate::modbus::slave_framer_test {
namespace {

using namespace std::chrono_literals;
using modbus_serial::Framing;
using Kind = FramerEvent::Kind;
using std::chrono::microseconds;
using std::chrono::milliseconds;
using Time = SerialClock::time_point;

const Time kStart = Time{} + std::chrono::hours(1);

// 9600 baud, 8 data bits, even parity, 1 stop bit: 11 bits a character (Serial Line 2.5.1).
// Most tests here give each read's time as the time its bytes began on the wire (char_time 0,
// as on a pseudo-terminal); SlaveFramerRtu.AReadIsTakenToHaveBegunItsBytesEarlier the real one.
const LineTiming k9600Wire = line_timing(9600, 11);
const LineTiming k9600 = [] {
  LineTiming t = k9600Wire;
  t.char_time = {};
  return t;
}();
constexpr microseconds kChar9600{1146};  // 11 / 9600 s, rounded up
constexpr microseconds kT15_9600{1719};
constexpr microseconds kT35_9600{4011};

Bytes hex(const std::string& s) {
  Bytes out;
  std::istringstream in(s);
  std::string b;
  while (in >> b) out.push_back(static_cast<std::uint8_t>(std::stoul(b, nullptr, 16)));
  return out;
}
Bytes text(const std::string& s) {
  return Bytes(s.begin(), s.end());
}
Bytes cat(const Bytes& a, const Bytes& b) {
  Bytes out = a;
  out.insert(out.end(), b.begin(), b.end());
  return out;
}

const char* name(Kind k) {
  switch (k) {
    case Kind::request:
      return "request";
    case Kind::bad_checksum:
      return "bad_checksum";
    case Kind::broken:
      return "broken";
    case Kind::overrun:
      return "overrun";
  }
  return "?";
}

// An event as one comparable line: "request 8 @01 03 00 6B 00 03", "broken 3".
std::string show(const FramerEvent& e) {
  std::ostringstream o;
  o << name(e.kind) << ' ' << e.bytes;
  if (e.kind == Kind::request) {
    char buf[4];
    std::snprintf(buf, sizeof buf, "%02X", e.adu.address);
    o << " @" << buf;
    for (const auto b : e.adu.pdu) {
      std::snprintf(buf, sizeof buf, "%02X", b);
      o << ' ' << buf;
    }
  }
  return o.str();
}
std::string request(std::size_t bytes, const std::string& address_and_pdu) {
  return "request " + std::to_string(bytes) + " @" + address_and_pdu;
}
std::string event(Kind k, std::size_t bytes) {
  return std::string(name(k)) + ' ' + std::to_string(bytes);
}

// A framer and a clock: bytes fed at times, the events collected as they come.
class Line {
 public:
  Line(Framing framing, Delimit delimit, LineTiming timing = k9600)
      : framer_(framing, delimit, timing) {}

  // `bytes` in one read, `after` since the last read (or since the start).
  void feed(const Bytes& bytes, microseconds after = 0us) {
    now_ += after;
    framer_.feed(bytes, now_);
    fed_ += bytes.size();
    collect();
  }
  // One byte at a time, `gap` apart (the first `first` after the last read).
  void trickle(const Bytes& bytes, microseconds gap, microseconds first = 0us) {
    for (std::size_t i = 0; i < bytes.size(); ++i) feed(Bytes{bytes[i]}, i == 0 ? first : gap);
  }
  // `d` passes with nothing received.
  void wait(microseconds d) {
    now_ += d;
    framer_.expire(now_);
    collect();
  }
  // Everything ends: a silence (or timeout) far longer than any.
  void settle() { wait(std::chrono::hours(1)); }

  [[nodiscard]] std::vector<std::string> shown() const {
    std::vector<std::string> out;
    for (const auto& e : events_) out.push_back(show(e));
    return out;
  }
  [[nodiscard]] std::size_t accounted() const {
    std::size_t n = 0;
    for (const auto& e : events_) n += e.bytes;
    return n;
  }
  [[nodiscard]] std::size_t fed() const { return fed_; }
  [[nodiscard]] const std::vector<FramerEvent>& events() const { return events_; }
  [[nodiscard]] Time now() const { return now_; }
  SlaveFramer& framer() { return framer_; }

 private:
  void collect() {
    while (auto e = framer_.next()) events_.push_back(std::move(*e));
  }

  SlaveFramer framer_;
  Time now_ = kStart;
  std::size_t fed_ = 0;
  std::vector<FramerEvent> events_;
};

// Settles the line and checks that every byte fed is in exactly one event.
#define EXPECT_ALL_BYTES_ACCOUNTED(line)         \
  do {                                           \
    (line).settle();                             \
    EXPECT_EQ((line).accounted(), (line).fed()); \
  } while (0)

// --- Golden vectors -----------------------------------------------------------------------------

struct Golden {
  const char* name;
  Bytes wire;       // the RTU frame: address, PDU, CRC low byte first (Serial Line 6.2.2)
  std::string adu;  // address and PDU as show() prints them
};

// Application Protocol examples, for slave 1 (and 17, the reference guide's, and 0, a broadcast).
const std::vector<Golden>& goldens() {
  static const std::vector<Golden> g = {
      // 6.3 Read Holding Registers: registers 108..110.
      {"read_holding_registers", hex("01 03 00 6B 00 03 74 17"), "01 03 00 6B 00 03"},
      {"read_holding_registers_slave17", hex("11 03 00 6B 00 03 76 87"), "11 03 00 6B 00 03"},
      // 6.6 Write Single Register: register 2 <- 0x0003.
      {"write_single_register", hex("01 06 00 01 00 03 98 0B"), "01 06 00 01 00 03"},
      // 6.6 again, as a broadcast (Serial Line 2.2: address 0).
      {"write_single_register_broadcast", hex("00 06 00 01 00 03 99 DA"), "00 06 00 01 00 03"},
      // 6.1 Read Coils: coils 20..38.
      {"read_coils", hex("01 01 00 13 00 13 8C 02"), "01 01 00 13 00 13"},
      // 6.12 Write Multiple Registers: registers 2, 3 <- 0x000A, 0x0102 (length from its byte
      // count).
      {"write_multiple_registers", hex("01 10 00 01 00 02 04 00 0A 01 02 92 30"),
       "01 10 00 01 00 02 04 00 0A 01 02"},
      // 6.8 Diagnostics, sub-function 00 Return Query Data, data A5 37 (length from its CRC).
      {"diagnostics_return_query_data", hex("01 08 00 00 A5 37 DA 8D"), "01 08 00 00 A5 37"},
  };
  return g;
}

class SlaveFramerGolden : public ::testing::TestWithParam<Golden> {};

TEST_P(SlaveFramerGolden, TheCodecEncodesTheVector) {
  const Golden& g = GetParam();
  const Bytes body(g.wire.begin(), g.wire.end() - 2);
  const Bytes pdu(body.begin() + 1, body.end());
  EXPECT_EQ(modbus_serial::encode(Framing::rtu, body[0], pdu), g.wire);
  EXPECT_TRUE(crc16_modbus_holds(g.wire));
}

TEST_P(SlaveFramerGolden, OneReadIsOneRequestRepliedAfterT35) {
  const Golden& g = GetParam();
  Line line(Framing::rtu, Delimit::silence);
  line.feed(g.wire, 10ms);
  // Taken as soon as its length and CRC are in, before the silence.
  ASSERT_EQ(line.shown(), std::vector<std::string>{request(g.wire.size(), g.adu)});
  // Serial Line 2.5.1.1: the reply may start 3.5 characters after the request's last byte.
  EXPECT_EQ(line.events()[0].reply_at, line.now() + kT35_9600);
  EXPECT_ALL_BYTES_ACCOUNTED(line);
  EXPECT_EQ(line.events().size(), 1u);
}

TEST_P(SlaveFramerGolden, ByteByByteIsOneRequestRepliedAfterT35) {
  const Golden& g = GetParam();
  for (const microseconds gap : {0us, kChar9600, kT15_9600}) {  // t1.5 itself is not "more than"
    SCOPED_TRACE(gap.count());
    Line line(Framing::rtu, Delimit::silence);
    line.trickle(g.wire, gap, 10ms);
    ASSERT_EQ(line.shown(), std::vector<std::string>{request(g.wire.size(), g.adu)});
    EXPECT_EQ(line.events()[0].reply_at, line.now() + kT35_9600);  // the last byte's time + t3.5
    EXPECT_ALL_BYTES_ACCOUNTED(line);
    EXPECT_EQ(line.events().size(), 1u);
  }
}

TEST_P(SlaveFramerGolden, TwoReadsSplitAtEveryByteAreOneRequest) {
  const Golden& g = GetParam();
  for (std::size_t cut = 1; cut < g.wire.size(); ++cut) {
    SCOPED_TRACE(cut);
    Line line(Framing::rtu, Delimit::silence);
    line.feed(Bytes(g.wire.begin(), g.wire.begin() + static_cast<long>(cut)), 10ms);
    EXPECT_TRUE(line.events().empty());
    // Buffered: a silence would end it.
    EXPECT_EQ(line.framer().deadline(), line.now() + kT35_9600);
    line.feed(Bytes(g.wire.begin() + static_cast<long>(cut), g.wire.end()), kChar9600);
    ASSERT_EQ(line.shown(), std::vector<std::string>{request(g.wire.size(), g.adu)});
    EXPECT_EQ(line.events()[0].reply_at, line.now() + kT35_9600);
    EXPECT_ALL_BYTES_ACCOUNTED(line);
    EXPECT_EQ(line.events().size(), 1u);
  }
}

TEST_P(SlaveFramerGolden, RtuOverTcpSplitAtEveryByteIsOneRequest) {
  const Golden& g = GetParam();
  for (std::size_t cut = 0; cut < g.wire.size(); ++cut) {
    SCOPED_TRACE(cut);
    Line line(Framing::rtu, Delimit::length);
    // Any time between the reads: a byte stream has no line timing.
    line.feed(Bytes(g.wire.begin(), g.wire.begin() + static_cast<long>(cut)), 10ms);
    EXPECT_EQ(line.framer().deadline(), std::nullopt);
    line.feed(Bytes(g.wire.begin() + static_cast<long>(cut), g.wire.end()), 5s);
    ASSERT_EQ(line.shown(), std::vector<std::string>{request(g.wire.size(), g.adu)});
    EXPECT_EQ(line.events()[0].reply_at, line.now());  // no silence to wait for
    EXPECT_ALL_BYTES_ACCOUNTED(line);
  }
}

TEST_P(SlaveFramerGolden, AsciiSplitAtEveryByteIsOneRequest) {
  const Golden& g = GetParam();
  const Bytes body(g.wire.begin(), g.wire.end() - 2);
  const Bytes pdu(body.begin() + 1, body.end());
  const Bytes wire = modbus_serial::encode(Framing::ascii, body[0], pdu);
  ASSERT_EQ(wire.size(), 2 * (body.size() + 1) + 3);
  for (std::size_t cut = 1; cut < wire.size(); ++cut) {
    SCOPED_TRACE(cut);
    Line line(Framing::ascii, Delimit::silence);
    line.feed(Bytes(wire.begin(), wire.begin() + static_cast<long>(cut)), 10ms);
    EXPECT_TRUE(line.events().empty());
    line.feed(Bytes(wire.begin() + static_cast<long>(cut), wire.end()), 999ms);
    ASSERT_EQ(line.shown(), std::vector<std::string>{request(wire.size(), g.adu)});
    EXPECT_EQ(line.events()[0].reply_at, line.now());
    EXPECT_ALL_BYTES_ACCOUNTED(line);
  }
  Line line(Framing::ascii, Delimit::silence);
  line.trickle(wire, 1000ms);  // exactly the timeout is not "more than" it (2.5.2.1)
  EXPECT_EQ(line.shown(), std::vector<std::string>{request(wire.size(), g.adu)});
  EXPECT_ALL_BYTES_ACCOUNTED(line);
}

INSTANTIATE_TEST_SUITE_P(SlaveFramerExamples, SlaveFramerGolden, ::testing::ValuesIn(goldens()),
                         [](const auto& p) { return std::string(p.param.name); });

// --- Line timing (Serial Line 2.5.1.1) ----------------------------------------------------------

TEST(SlaveFramerTiming, CharacterTimesUpTo19200Baud) {
  // 9600 baud, 11 bits: one character 1145.8 us; 1.5 of them 1718.75 us, 3.5 of them 4010.4 us,
  // rounded up to whole microseconds (a slave waits at least the time).
  EXPECT_EQ(k9600.t15, 1719us);
  EXPECT_EQ(k9600.t35, 4011us);
  EXPECT_EQ(k9600.ascii_timeout, 1000ms);
  // 8N1 (10 bits) at 9600: one character 1041.7 us.
  EXPECT_EQ(line_timing(9600, 10).t15, 1563us);
  EXPECT_EQ(line_timing(9600, 10).t35, 3647us);
  // 19200 is not "greater than 19200": still computed (573 us a character).
  EXPECT_EQ(line_timing(19200, 11).t15, 860us);
  EXPECT_EQ(line_timing(19200, 11).t35, 2006us);
  // 1200 baud: 9166.7 us a character.
  EXPECT_EQ(line_timing(1200, 11).t15, 13751us);
  EXPECT_EQ(line_timing(1200, 11).t35, 32085us);
}

TEST(SlaveFramerTiming, FixedAbove19200Baud) {
  for (const unsigned baud : {19201u, 38400u, 57600u, 115200u, 921600u}) {
    SCOPED_TRACE(baud);
    const LineTiming t = line_timing(baud, 11);
    EXPECT_EQ(t.t15, 750us);
    EXPECT_EQ(t.t35, 1750us);
    EXPECT_EQ(t.ascii_timeout, 1000ms);
  }
}

TEST(SlaveFramerTiming, FixedTimesRuleAFastLine) {
  Line line(Framing::rtu, Delimit::silence, line_timing(115200, 11));
  const Bytes f = hex("01 03 00 6B 00 03 74 17");
  line.trickle(f, 750us, 1ms);
  ASSERT_EQ(line.shown(), std::vector<std::string>{request(8, "01 03 00 6B 00 03")});
  EXPECT_EQ(line.events()[0].reply_at, line.now() + 1750us);
  // A gap of 751 us inside the next frame (after a 1.75 ms silence) breaks it.
  line.feed(Bytes(f.begin(), f.begin() + 3), 1750us);
  line.feed(Bytes(f.begin() + 3, f.end()), 751us);
  line.wait(1749us);
  EXPECT_EQ(line.events().size(), 1u);
  line.wait(1us);
  EXPECT_EQ(line.shown(),
            (std::vector<std::string>{request(8, "01 03 00 6B 00 03"), event(Kind::broken, 8)}));
  EXPECT_ALL_BYTES_ACCOUNTED(line);
}

// --- RTU on a line: gaps, silences, bad frames --------------------------------------------------

const Bytes kRead = hex("01 03 00 6B 00 03 74 17");   // Application Protocol 6.3
const Bytes kWrite = hex("01 06 00 01 00 03 98 0B");  // Application Protocol 6.6
const std::string kReadAdu = "01 03 00 6B 00 03";
const std::string kWriteAdu = "01 06 00 01 00 03";

// A USB adapter or a busy kernel hands over several characters in one read, when the last has
// arrived: the silence before the read is measured to where its first byte began on the wire
// (n characters earlier). A frame on the wire without a gap, read in two halves, is one request;
// with 2 characters of silence between the halves (more than 1.5) it is discarded.
// A frame less than 3.5 characters after a request is not a request while the line should be
// silent; once the host has sent its reply (replied()), the master's next request is taken however
// soon it comes (a pseudo-terminal delivers it the moment it was written).
TEST(SlaveFramerRtu, TheNextRequestRightAfterOurReplyIsTaken) {
  for (const bool replied : {false, true}) {
    SCOPED_TRACE(replied);
    Line line(Framing::rtu, Delimit::silence);
    line.feed(kRead, 10ms);
    if (replied) line.framer().replied();
    line.feed(kWrite, kT15_9600);
    line.settle();
    if (replied) {
      EXPECT_EQ(line.shown(), (std::vector<std::string>{request(8, kReadAdu), request(8, kWriteAdu)}));
    } else {
      EXPECT_EQ(line.shown(), (std::vector<std::string>{request(8, kReadAdu), event(Kind::broken, 8)}));
    }
    EXPECT_ALL_BYTES_ACCOUNTED(line);
  }
}

// A port that hands bytes over late (LineTiming::latency: a UART's FIFO, a USB latency timer): a
// frame whose tail comes 10 ms after its head is one request when the port may be 20 ms late,
// and is cut (discarded) when the framer goes by the specification's 1.5 / 3.5 characters alone.
TEST(SlaveFramerRtu, APortsLatencyIsNoGapInsideAFrame) {
  for (const auto latency : {0ms, 20ms}) {
    SCOPED_TRACE(latency.count());
    LineTiming t = k9600;
    t.latency = latency;
    Line line(Framing::rtu, Delimit::silence, t);
    line.feed(Bytes(kRead.begin(), kRead.begin() + 5), 10ms);
    if (latency > 0ms) {
      EXPECT_EQ(line.framer().deadline(), line.now() + 20ms);
    }
    line.feed(Bytes(kRead.begin() + 5, kRead.end()), 10ms);
    line.settle();
    if (latency > 0ms) {
      EXPECT_EQ(line.shown(), std::vector<std::string>{request(8, kReadAdu)});
    } else {
      EXPECT_EQ(line.shown(), (std::vector<std::string>{event(Kind::broken, 5),
                                                        event(Kind::broken, 3)}));
    }
    EXPECT_ALL_BYTES_ACCOUNTED(line);
  }
}

TEST(SlaveFramerRtu, AReadIsTakenToHaveBegunItsBytesEarlier) {
  EXPECT_EQ(k9600Wire.char_time, 1145us);  // 11 / 9600 s, rounded down
  for (const auto silence : {0us, 2 * kChar9600}) {
    SCOPED_TRACE(silence.count());
    Line line(Framing::rtu, Delimit::silence, k9600Wire);
    const Bytes first(kRead.begin(), kRead.begin() + 4);
    const Bytes second(kRead.begin() + 4, kRead.end());
    line.feed(first, 10ms);
    line.feed(second, 4 * k9600Wire.char_time + silence);  // 4 more characters' time
    line.settle();
    if (silence == 0us) {
      EXPECT_EQ(line.shown(), std::vector<std::string>{request(8, kReadAdu)});
    } else {
      EXPECT_EQ(line.shown(), std::vector<std::string>{event(Kind::broken, 8)});
    }
    EXPECT_ALL_BYTES_ACCOUNTED(line);
  }
}

TEST(SlaveFramerRtu, GapOverT15InsideAFrameDiscardsItAndTheNextFrameIsTaken) {
  for (std::size_t cut = 1; cut < kRead.size(); ++cut) {
    SCOPED_TRACE(cut);
    Line line(Framing::rtu, Delimit::silence);
    line.trickle(Bytes(kRead.begin(), kRead.begin() + static_cast<long>(cut)), kChar9600, 10ms);
    line.trickle(Bytes(kRead.begin() + static_cast<long>(cut), kRead.end()), kChar9600,
                 kT15_9600 + 1us);
    // Whole and with a good CRC, but cut: not a request (Serial Line 2.5.1.1).
    EXPECT_TRUE(line.events().empty());
    EXPECT_EQ(line.framer().deadline(), line.now() + kT35_9600);
    line.wait(kT35_9600 - 1us);
    EXPECT_TRUE(line.events().empty());
    line.wait(1us);
    EXPECT_EQ(line.shown(), std::vector<std::string>{event(Kind::broken, 8)});
    EXPECT_EQ(line.framer().deadline(), std::nullopt);
    // After the 3.5-character silence, the next frame is good.
    line.feed(kWrite);
    EXPECT_EQ(line.shown(),
              (std::vector<std::string>{event(Kind::broken, 8), request(8, kWriteAdu)}));
    EXPECT_ALL_BYTES_ACCOUNTED(line);
  }
}

TEST(SlaveFramerRtu, AFrameCutByAGapIsBrokenEvenWhenTheBytesDoNotCheck) {
  // The master gives up on a frame half-sent and sends it again after a gap shorter than t3.5:
  // the line was never silent for 3.5 characters, so it is all one discarded run, and it was cut
  // by a gap (broken), not a frame that failed its CRC (bad_checksum: FC 08 0x0C counts those).
  Line line(Framing::rtu, Delimit::silence);
  line.trickle(Bytes(kRead.begin(), kRead.begin() + 4), kChar9600, 10ms);
  line.trickle(kRead, kChar9600, 2 * kChar9600);
  line.wait(kT35_9600);
  EXPECT_EQ(line.shown(), std::vector<std::string>{event(Kind::broken, 12)});
  EXPECT_ALL_BYTES_ACCOUNTED(line);
}

TEST(SlaveFramerRtu, BadCrcIsBadChecksumAndSkipsToTheNextSilence) {
  Bytes bad = kRead;
  bad.back() ^= 0x01;
  Line line(Framing::rtu, Delimit::silence);
  line.trickle(bad, kChar9600, 10ms);
  EXPECT_TRUE(line.events().empty());  // one event for the whole run, at its silence
  // What follows before a silence, even a good frame, is skipped with it.
  line.trickle(kWrite, kChar9600, kChar9600);
  line.feed(hex("FF 00"), kT15_9600);
  EXPECT_TRUE(line.events().empty());
  EXPECT_EQ(line.framer().deadline(), line.now() + kT35_9600);
  line.wait(kT35_9600);
  EXPECT_EQ(line.shown(), std::vector<std::string>{event(Kind::bad_checksum, 18)});
  line.feed(kWrite, 1s);
  EXPECT_EQ(line.shown(),
            (std::vector<std::string>{event(Kind::bad_checksum, 18), request(8, kWriteAdu)}));
  EXPECT_ALL_BYTES_ACCOUNTED(line);
}

TEST(SlaveFramerRtu, BadCrcInOneReadThenTheSilenceComesWithTheNextRead) {
  Bytes bad = kWrite;
  bad[5] ^= 0x80;  // the value, so the CRC no longer holds
  Line line(Framing::rtu, Delimit::silence);
  line.feed(bad, 10ms);
  line.feed(kRead, kT35_9600);  // the silence is seen when the next read comes
  EXPECT_EQ(line.shown(),
            (std::vector<std::string>{event(Kind::bad_checksum, 8), request(8, kReadAdu)}));
  EXPECT_ALL_BYTES_ACCOUNTED(line);
}

TEST(SlaveFramerRtu, NoiseThenSilenceThenAGoodFrame) {
  struct Noise {
    const char* what;
    Bytes bytes;
  };
  for (const Noise& n : {Noise{"reserved addresses", hex("FF FE F8")},
                         Noise{"a frame's start", hex("01 03 00")}, Noise{"one byte", hex("00")}}) {
    SCOPED_TRACE(n.what);
    for (const bool by_byte : {false, true}) {
      Line line(Framing::rtu, Delimit::silence);
      if (by_byte) {
        line.trickle(n.bytes, kChar9600, 10ms);
      } else {
        line.feed(n.bytes, 10ms);
      }
      EXPECT_TRUE(line.events().empty());
      line.trickle(kRead, kChar9600, kT35_9600);
      EXPECT_EQ(line.shown(), (std::vector<std::string>{event(Kind::broken, n.bytes.size()),
                                                        request(8, kReadAdu)}));
      EXPECT_EQ(line.events()[1].reply_at, line.now() + kT35_9600);
      EXPECT_ALL_BYTES_ACCOUNTED(line);
    }
  }
}

TEST(SlaveFramerRtu, SilenceOfExactlyT35EndsAFrame) {
  Line line(Framing::rtu, Delimit::silence);
  line.feed(hex("01 03 00"), 10ms);
  EXPECT_EQ(line.framer().deadline(), line.now() + kT35_9600);
  line.wait(kT35_9600 - 1us);
  EXPECT_TRUE(line.events().empty());
  line.wait(1us);
  EXPECT_EQ(line.shown(), std::vector<std::string>{event(Kind::broken, 3)});
  line.feed(kRead, kT35_9600);
  EXPECT_EQ(line.events().size(), 2u);
  EXPECT_ALL_BYTES_ACCOUNTED(line);
}

TEST(SlaveFramerRtu, FramesOneT35ApartAreBothTaken) {
  Line line(Framing::rtu, Delimit::silence);
  line.feed(kRead, 10ms);
  EXPECT_EQ(line.framer().deadline(), std::nullopt);  // nothing buffered
  line.feed(kWrite, kT35_9600);
  EXPECT_EQ(line.shown(), (std::vector<std::string>{request(8, kReadAdu), request(8, kWriteAdu)}));
  EXPECT_EQ(line.events()[1].reply_at, line.now() + kT35_9600);
  EXPECT_ALL_BYTES_ACCOUNTED(line);
}

// A frame must be followed by 3.5 characters of silence (Serial Line 2.5.1.1): bytes that come
// sooner are not a request, however they were split into reads.
TEST(SlaveFramerRtu, BytesBeforeTheSilenceAfterARequestAreDiscardedHoweverSplit) {
  const Bytes both = cat(kRead, kWrite);
  const std::vector<std::string> want{request(8, kReadAdu), event(Kind::broken, 8)};
  {
    Line line(Framing::rtu, Delimit::silence);
    line.feed(both, 10ms);
    line.wait(kT35_9600);
    EXPECT_EQ(line.shown(), want);
    EXPECT_ALL_BYTES_ACCOUNTED(line);
  }
  for (const microseconds gap : {0us, kChar9600, kT15_9600}) {
    SCOPED_TRACE(gap.count());
    Line line(Framing::rtu, Delimit::silence);
    line.trickle(both, gap, 10ms);
    line.wait(kT35_9600);
    EXPECT_EQ(line.shown(), want);
    EXPECT_ALL_BYTES_ACCOUNTED(line);
  }
  for (std::size_t cut = 1; cut < both.size(); ++cut) {
    SCOPED_TRACE(cut);
    Line line(Framing::rtu, Delimit::silence);
    line.feed(Bytes(both.begin(), both.begin() + static_cast<long>(cut)), 10ms);
    line.feed(Bytes(both.begin() + static_cast<long>(cut), both.end()), kChar9600);
    line.wait(kT35_9600);
    EXPECT_EQ(line.shown(), want);
    EXPECT_ALL_BYTES_ACCOUNTED(line);
  }
  // Between t1.5 and t3.5 after the request: still not the silence a frame needs before it.
  Line line(Framing::rtu, Delimit::silence);
  line.feed(kRead, 10ms);
  line.feed(kWrite, kT35_9600 - 1us);
  EXPECT_EQ(line.framer().deadline(), line.now() + kT35_9600);
  line.wait(kT35_9600);
  EXPECT_EQ(line.shown(), want);
  line.feed(kWrite, kT35_9600);  // and after one, it is a request
  EXPECT_EQ(line.shown(), (std::vector<std::string>{request(8, kReadAdu), event(Kind::broken, 8),
                                                    request(8, kWriteAdu)}));
  EXPECT_ALL_BYTES_ACCOUNTED(line);
}

// Serial Line 2.5.1.1: an RTU frame is at most 256 bytes.
Bytes run_of(std::size_t n, Bytes start) {
  for (std::size_t i = start.size(); i < n; ++i) {
    start.push_back(static_cast<std::uint8_t>(i * 13 + 5));
  }
  start.resize(n);
  return start;
}

TEST(SlaveFramerRtu, MoreThan256BytesWithoutASilenceIsAnOverrun) {
  struct Case {
    const char* what;
    Bytes start;
  };
  // A known function whose CRC fails at its 8th byte, and one the codec delimits by its CRC,
  // which never holds here (checked apart: no prefix of these runs ends in a good CRC).
  for (const Case& c : {Case{"read holding registers", hex("01 03 00 00 00 00")},
                        Case{"user function 0x41", hex("01 41")}}) {
    SCOPED_TRACE(c.what);
    for (const std::size_t chunk : {std::size_t{1}, std::size_t{30}, std::size_t{300}}) {
      SCOPED_TRACE(chunk);
      const Bytes run = run_of(300, c.start);
      Line line(Framing::rtu, Delimit::silence);
      for (std::size_t at = 0; at < run.size(); at += chunk) {
        const std::size_t n = std::min(chunk, run.size() - at);
        line.feed(
            Bytes(run.begin() + static_cast<long>(at), run.begin() + static_cast<long>(at + n)),
            // A read's bytes arrive at its time (slave_framer.h): one character after the last.
            at == 0 ? microseconds(10ms) : kChar9600);
      }
      EXPECT_TRUE(line.events().empty());
      line.wait(kT35_9600);
      EXPECT_EQ(line.shown(), std::vector<std::string>{event(Kind::overrun, 300)});
      line.feed(kRead, 1s);
      EXPECT_EQ(line.shown(),
                (std::vector<std::string>{event(Kind::overrun, 300), request(8, kReadAdu)}));
      EXPECT_ALL_BYTES_ACCOUNTED(line);
    }
  }
}

TEST(SlaveFramerRtu, OverrunStartsAt257Bytes) {
  {
    Line line(Framing::rtu, Delimit::silence);
    line.feed(run_of(256, hex("01 03 00 00 00 00")), 10ms);
    line.wait(kT35_9600);
    EXPECT_EQ(line.shown(), std::vector<std::string>{event(Kind::bad_checksum, 256)});
    EXPECT_ALL_BYTES_ACCOUNTED(line);
  }
  {
    Line line(Framing::rtu, Delimit::silence);
    line.feed(run_of(257, hex("01 03 00 00 00 00")), 10ms);
    line.wait(kT35_9600);
    EXPECT_EQ(line.shown(), std::vector<std::string>{event(Kind::overrun, 257)});
    EXPECT_ALL_BYTES_ACCOUNTED(line);
  }
}

TEST(SlaveFramerRtu, TheLongestFrameIsARequest) {
  // A user-defined function (Application Protocol 5: 65..72) with a 253-byte PDU: 256 bytes,
  // delimited by its CRC.
  Bytes pdu{0x41};
  for (std::size_t i = 0; i < 252; ++i) pdu.push_back(static_cast<std::uint8_t>(i * 7 + 3));
  const Bytes wire = modbus_serial::encode(Framing::rtu, 0x01, pdu);
  ASSERT_EQ(wire.size(), 256u);
  EXPECT_EQ(wire[254], 0x1F);  // its CRC, computed apart
  EXPECT_EQ(wire[255], 0x21);
  Line line(Framing::rtu, Delimit::silence);
  line.trickle(wire, kChar9600, 10ms);
  ASSERT_EQ(line.events().size(), 1u);
  EXPECT_EQ(line.events()[0].kind, Kind::request);
  EXPECT_EQ(line.events()[0].bytes, 256u);
  EXPECT_EQ(line.events()[0].adu.address, 0x01);
  EXPECT_EQ(line.events()[0].adu.pdu, pdu);
  EXPECT_ALL_BYTES_ACCOUNTED(line);
}

TEST(SlaveFramerRtu, ResetDropsWhatIsBuffered) {
  Line line(Framing::rtu, Delimit::silence);
  line.feed(hex("01 03 00"), 10ms);
  line.framer().reset();
  EXPECT_EQ(line.framer().deadline(), std::nullopt);
  line.wait(1s);
  EXPECT_TRUE(line.events().empty());
  line.feed(kRead, 1ms);  // no silence needed after a reset: the port was reopened
  EXPECT_EQ(line.shown(), std::vector<std::string>{request(8, kReadAdu)});
}

// --- RTU over TCP (Delimit::length) -------------------------------------------------------------

TEST(SlaveFramerLength, TwoFramesBackToBackInOneRead) {
  Line line(Framing::rtu, Delimit::length);
  line.feed(cat(kRead, kWrite), 10ms);
  EXPECT_EQ(line.shown(), (std::vector<std::string>{request(8, kReadAdu), request(8, kWriteAdu)}));
  EXPECT_EQ(line.events()[0].reply_at, line.now());
  EXPECT_EQ(line.events()[1].reply_at, line.now());
  EXPECT_EQ(line.framer().deadline(), std::nullopt);
  EXPECT_ALL_BYTES_ACCOUNTED(line);
}

TEST(SlaveFramerLength, BytesThatCannotStartAFrameAreDroppedOneByOne) {
  Line line(Framing::rtu, Delimit::length);
  line.feed(cat(cat(hex("FF F8"), kRead), cat(hex("FE"), kWrite)), 10ms);
  EXPECT_EQ(line.shown(), (std::vector<std::string>{event(Kind::broken, 1), event(Kind::broken, 1),
                                                    request(8, kReadAdu), event(Kind::broken, 1),
                                                    request(8, kWriteAdu)}));
  EXPECT_ALL_BYTES_ACCOUNTED(line);
}

TEST(SlaveFramerLength, BadCrcDropsTheFrameAndTheNextIsTaken) {
  Bytes bad = kRead;
  bad[6] ^= 0xFF;
  Line line(Framing::rtu, Delimit::length);
  line.feed(cat(bad, kWrite), 10ms);
  EXPECT_EQ(line.shown(),
            (std::vector<std::string>{event(Kind::bad_checksum, 8), request(8, kWriteAdu)}));
  EXPECT_ALL_BYTES_ACCOUNTED(line);
}

TEST(SlaveFramerLength, NoTimeoutEndsAPartialFrame) {
  Line line(Framing::rtu, Delimit::length);
  line.feed(Bytes(kRead.begin(), kRead.begin() + 5), 10ms);
  line.wait(std::chrono::hours(2));
  EXPECT_TRUE(line.events().empty());
  line.feed(Bytes(kRead.begin() + 5, kRead.end()), 1ms);
  EXPECT_EQ(line.shown(), std::vector<std::string>{request(8, kReadAdu)});
  EXPECT_ALL_BYTES_ACCOUNTED(line);
}

// The header: "the connection's stream is resynced on the next read that starts with a good
// frame": what a read left that cannot end in a frame is dropped.
TEST(SlaveFramerLength, ResyncsOnAReadThatStartsWithAGoodFrame) {
  Line line(Framing::rtu, Delimit::length);
  line.feed(hex("01 03 00"), 10ms);  // looks like a frame's start, and never finishes
  EXPECT_TRUE(line.events().empty());
  line.feed(cat(kRead, kWrite), 10ms);
  EXPECT_EQ(line.shown(), (std::vector<std::string>{event(Kind::broken, 3), request(8, kReadAdu),
                                                    request(8, kWriteAdu)}));
  EXPECT_ALL_BYTES_ACCOUNTED(line);
}

// --- ASCII (Serial Line 2.5.2.1, LRC 6.2.1) -----------------------------------------------------

// Application Protocol 6.3's request for slave 17, the reference guide's ASCII example: LRC 7E.
const Bytes kAscii = text(":1103006B00037E\r\n");
const std::string kAsciiAdu = "11 03 00 6B 00 03";

TEST(SlaveFramerAscii, GoldenFrame) {
  EXPECT_EQ(modbus_serial::encode(Framing::ascii, 0x11, hex("03 00 6B 00 03")), kAscii);
  EXPECT_EQ(modbus_serial::lrc(hex("11 03 00 6B 00 03")), 0x7E);
  Line line(Framing::ascii, Delimit::silence);
  line.feed(kAscii, 10ms);
  ASSERT_EQ(line.shown(), std::vector<std::string>{request(17, kAsciiAdu)});
  EXPECT_EQ(line.events()[0].reply_at, line.now());  // ASCII has no silence to wait for
  EXPECT_EQ(line.framer().deadline(), std::nullopt);
  EXPECT_ALL_BYTES_ACCOUNTED(line);
}

TEST(SlaveFramerAscii, SplitAtEveryByte) {
  for (std::size_t cut = 1; cut < kAscii.size(); ++cut) {
    SCOPED_TRACE(cut);
    Line line(Framing::ascii, Delimit::silence);
    line.feed(Bytes(kAscii.begin(), kAscii.begin() + static_cast<long>(cut)), 10ms);
    EXPECT_TRUE(line.events().empty());
    EXPECT_EQ(line.framer().deadline(), line.now() + 1s + 1us);
    line.feed(Bytes(kAscii.begin() + static_cast<long>(cut), kAscii.end()), 500ms);
    EXPECT_EQ(line.shown(), std::vector<std::string>{request(17, kAsciiAdu)});
    EXPECT_ALL_BYTES_ACCOUNTED(line);
  }
  Line line(Framing::ascii, Delimit::silence);
  line.trickle(kAscii, 200ms, 10ms);
  EXPECT_EQ(line.shown(), std::vector<std::string>{request(17, kAsciiAdu)});
  EXPECT_ALL_BYTES_ACCOUNTED(line);
}

TEST(SlaveFramerAscii, LowercaseHexIsAccepted) {
  Line line(Framing::ascii, Delimit::silence);
  line.feed(text(":1103006b00037e\r\n"), 10ms);
  EXPECT_EQ(line.shown(), std::vector<std::string>{request(17, kAsciiAdu)});
  EXPECT_ALL_BYTES_ACCOUNTED(line);
}

TEST(SlaveFramerAscii, BadLrcIsBadChecksum) {
  Line line(Framing::ascii, Delimit::silence);
  line.feed(text(":1103006B00037F\r\n"), 10ms);
  EXPECT_EQ(line.shown(), std::vector<std::string>{event(Kind::bad_checksum, 17)});
  line.feed(kAscii, 10ms);  // no silence needed in ASCII: the next ':' starts the next frame
  EXPECT_EQ(line.shown(),
            (std::vector<std::string>{event(Kind::bad_checksum, 17), request(17, kAsciiAdu)}));
  EXPECT_ALL_BYTES_ACCOUNTED(line);
}

TEST(SlaveFramerAscii, AColonRestartsAFrame) {
  const Bytes wire = cat(text(":1103006B"), kAscii);
  for (std::size_t cut = 0; cut <= wire.size(); ++cut) {
    SCOPED_TRACE(cut);
    Line line(Framing::ascii, Delimit::silence);
    line.feed(Bytes(wire.begin(), wire.begin() + static_cast<long>(cut)), 10ms);
    line.feed(Bytes(wire.begin() + static_cast<long>(cut), wire.end()), 10ms);
    EXPECT_EQ(line.shown(),
              (std::vector<std::string>{event(Kind::broken, 9), request(17, kAsciiAdu)}));
    EXPECT_ALL_BYTES_ACCOUNTED(line);
  }
}

TEST(SlaveFramerAscii, MoreThanOneSecondBetweenCharactersDiscardsTheFrame) {
  Line line(Framing::ascii, Delimit::silence);
  line.feed(text(":1103006B00"), 10ms);
  EXPECT_EQ(line.framer().deadline(), line.now() + 1s + 1us);
  line.wait(1s);
  EXPECT_TRUE(line.events().empty());  // exactly 1 s is not more than it
  line.wait(1us);
  EXPECT_EQ(line.shown(), std::vector<std::string>{event(Kind::broken, 11)});
  EXPECT_EQ(line.framer().deadline(), std::nullopt);
  // Its tail, late, is noise: it does not start with ':'.
  line.feed(text("037E\r\n"), 1ms);
  EXPECT_EQ(line.shown(),
            (std::vector<std::string>{event(Kind::broken, 11), event(Kind::broken, 6)}));
  line.feed(kAscii, 1ms);
  EXPECT_EQ(line.shown(), (std::vector<std::string>{event(Kind::broken, 11), event(Kind::broken, 6),
                                                    request(17, kAsciiAdu)}));
  EXPECT_ALL_BYTES_ACCOUNTED(line);
}

TEST(SlaveFramerAscii, TheTimeoutIsSeenWhenTheNextCharacterComes) {
  Line line(Framing::ascii, Delimit::silence);
  line.feed(text(":1103006B00"), 10ms);
  line.feed(kAscii, 1s + 1us);  // no expire() in between
  EXPECT_EQ(line.shown(),
            (std::vector<std::string>{event(Kind::broken, 11), request(17, kAsciiAdu)}));
  EXPECT_ALL_BYTES_ACCOUNTED(line);
}

TEST(SlaveFramerAscii, NoiseBeforeTheColonIsBroken) {
  Line line(Framing::ascii, Delimit::silence);
  line.feed(cat(text("\r\nxyz"), kAscii), 10ms);
  EXPECT_EQ(line.shown(),
            (std::vector<std::string>{event(Kind::broken, 5), request(17, kAsciiAdu)}));
  EXPECT_ALL_BYTES_ACCOUNTED(line);
}

TEST(SlaveFramerAscii, MoreThan513CharactersIsAnOverrun) {
  // Serial Line 2.5.2.1: an ASCII frame is at most 513 characters.
  Bytes wire = text(":");
  wire.resize(601, '0');
  wire.push_back('\r');
  wire.push_back('\n');
  Line line(Framing::ascii, Delimit::silence);
  line.feed(wire, 10ms);
  line.feed(kAscii, 10ms);
  ASSERT_EQ(line.events().size(), 3u) << ::testing::PrintToString(line.shown());
  EXPECT_EQ(show(line.events()[0]), event(Kind::overrun, 513));
  EXPECT_EQ(show(line.events()[1]), event(Kind::broken, 603 - 513));  // its tail: noise
  EXPECT_EQ(show(line.events()[2]), request(17, kAsciiAdu));
  EXPECT_ALL_BYTES_ACCOUNTED(line);
}

}  // namespace
}  // namespace drivegate::modbus::slave_framer_test
