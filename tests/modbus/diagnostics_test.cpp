// FC 08 Diagnostics answered from a serial listener's counters (diagnostics.h), against the
// "MODBUS Application Protocol Specification V1.1b3" ("Application Protocol"), 6.8 and 6.8.1:
// request and normal response are function 08, a 2-byte sub-function, 2-byte data; the
// exception reply is 88 and its code (7).
#include "diagnostics.h"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <vector>

namespace drivegate::modbus {
namespace {

using Bytes = std::vector<std::uint8_t>;

// The request PDU's answer, as bytes.
Bytes ask(const Bytes& request, const SerialCounters& counters, SerialCounters& cleared) {
  std::array<std::uint8_t, 253> out{};  // kMaxPduSize
  out.fill(0xEE);
  const std::size_t n = diagnostics(request, counters, cleared, out);
  EXPECT_LE(n, out.size());
  return Bytes(out.begin(), out.begin() + static_cast<long>(n));
}

// Distinct values everywhere, some past 16 bits.
SerialCounters some_counters() {
  SerialCounters c;
  c.bus_messages = 0x1'2345;
  c.bus_comm_errors = 17;
  c.bus_exception_errors = 3;
  c.server_messages = 0x1'0000;  // 65536: reads 0000
  c.server_no_response = 5;
  c.server_nak = 0;
  c.server_busy = 6;
  c.bus_char_overruns = 9;
  c.broken_frames = 11;
  c.other_units = 12;
  c.broadcasts = 13;
  c.broadcasts_refused = 14;
  c.write_timeouts = 15;
  return c;
}

bool same(const SerialCounters& a, const SerialCounters& b) {
  return a.bus_messages == b.bus_messages && a.bus_comm_errors == b.bus_comm_errors &&
         a.bus_exception_errors == b.bus_exception_errors &&
         a.server_messages == b.server_messages && a.server_no_response == b.server_no_response &&
         a.server_nak == b.server_nak && a.server_busy == b.server_busy &&
         a.bus_char_overruns == b.bus_char_overruns && a.broken_frames == b.broken_frames &&
         a.other_units == b.other_units && a.broadcasts == b.broadcasts &&
         a.broadcasts_refused == b.broadcasts_refused && a.write_timeouts == b.write_timeouts;
}

TEST(Diagnostics, ReturnQueryDataEchoesTheSpecExample) {
  // 6.8: request 08 00 00 A5 37, response 08 00 00 A5 37.
  SerialCounters counters = some_counters(), cleared;
  EXPECT_EQ(ask({0x08, 0x00, 0x00, 0xA5, 0x37}, counters, cleared),
            (Bytes{0x08, 0x00, 0x00, 0xA5, 0x37}));
  EXPECT_TRUE(same(cleared, SerialCounters{}));
}

TEST(Diagnostics, ReturnQueryDataEchoesAnyData) {
  SerialCounters counters = some_counters(), cleared;
  for (const Bytes& request :
       {Bytes{0x08, 0x00, 0x00, 0x00, 0x00}, Bytes{0x08, 0x00, 0x00, 0xFF, 0xFF, 0x01, 0x02},
        Bytes{0x08, 0x00, 0x00, 0x12, 0x34, 0x56},  // odd: as sent
        Bytes{0x08, 0x00, 0x00, 0xDE, 0xAD, 0xBE, 0xEF, 0x00, 0x0A}}) {
    EXPECT_EQ(ask(request, counters, cleared), request);
  }
  // The longest PDU (Application Protocol 4.1: 253 bytes).
  Bytes longest{0x08, 0x00, 0x00};
  for (std::size_t i = 3; i < 253; ++i) longest.push_back(static_cast<std::uint8_t>(i));
  EXPECT_EQ(ask(longest, counters, cleared), longest);
}

TEST(Diagnostics, CountersAreReturnedMinusClearedIn16Bits) {
  const SerialCounters counters = some_counters();
  SerialCounters cleared;
  cleared.bus_messages = 0x0001;   // 0x12345 - 1 = 0x12344: 2344
  cleared.bus_comm_errors = 7;     // 10
  cleared.server_no_response = 5;  // 0
  cleared.bus_char_overruns = 2;   // 7
  const SerialCounters before = cleared;
  struct Case {
    std::uint8_t sub;
    std::uint8_t hi, lo;
  };
  for (const Case& c : {Case{0x0B, 0x23, 0x44}, Case{0x0C, 0x00, 0x0A}, Case{0x0D, 0x00, 0x03},
                        Case{0x0E, 0x00, 0x00}, Case{0x0F, 0x00, 0x00}, Case{0x10, 0x00, 0x00},
                        Case{0x11, 0x00, 0x06}, Case{0x12, 0x00, 0x07}}) {
    SCOPED_TRACE(static_cast<int>(c.sub));
    EXPECT_EQ(ask({0x08, 0x00, c.sub, 0x00, 0x00}, counters, cleared),
              (Bytes{0x08, 0x00, c.sub, c.hi, c.lo}));
  }
  EXPECT_TRUE(same(cleared, before));  // reading moves nothing
}

TEST(Diagnostics, DifferenceWrapsAcross16Bits) {
  SerialCounters counters, cleared;
  counters.bus_messages = 0x1'0002;
  cleared.bus_messages = 0xFFFF;  // 3 messages since
  EXPECT_EQ(ask({0x08, 0x00, 0x0B, 0x00, 0x00}, counters, cleared),
            (Bytes{0x08, 0x00, 0x0B, 0x00, 0x03}));
  counters.bus_messages = 70000;  // 70000 mod 65536 = 4464 = 0x1170
  cleared.bus_messages = 0;
  EXPECT_EQ(ask({0x08, 0x00, 0x0B, 0x00, 0x00}, counters, cleared),
            (Bytes{0x08, 0x00, 0x0B, 0x11, 0x70}));
}

TEST(Diagnostics, ReturnDiagnosticRegisterIsZero) {
  SerialCounters counters = some_counters(), cleared;
  EXPECT_EQ(ask({0x08, 0x00, 0x02, 0x00, 0x00}, counters, cleared),
            (Bytes{0x08, 0x00, 0x02, 0x00, 0x00}));
}

TEST(Diagnostics, ClearCountersMovesClearedNotTheCounters) {
  const SerialCounters counters = some_counters();
  SerialCounters cleared;
  cleared.bus_messages = 1;
  // 6.8.1 0x0A: the echo of the request.
  EXPECT_EQ(ask({0x08, 0x00, 0x0A, 0x00, 0x00}, counters, cleared),
            (Bytes{0x08, 0x00, 0x0A, 0x00, 0x00}));
  EXPECT_TRUE(same(counters, some_counters()));  // const, and still what /metrics shows
  EXPECT_TRUE(same(cleared, counters));
  for (std::uint8_t sub = 0x0B; sub <= 0x12; ++sub) {
    SCOPED_TRACE(static_cast<int>(sub));
    EXPECT_EQ(ask({0x08, 0x00, sub, 0x00, 0x00}, counters, cleared),
              (Bytes{0x08, 0x00, sub, 0x00, 0x00}));
  }
  // Counting goes on from there.
  SerialCounters later = counters;
  later.bus_messages += 4;
  later.server_busy += 1;
  EXPECT_EQ(ask({0x08, 0x00, 0x0B, 0x00, 0x00}, later, cleared),
            (Bytes{0x08, 0x00, 0x0B, 0x00, 0x04}));
  EXPECT_EQ(ask({0x08, 0x00, 0x11, 0x00, 0x00}, later, cleared),
            (Bytes{0x08, 0x00, 0x11, 0x00, 0x01}));
}

TEST(Diagnostics, ClearOverrunCounterClearsOnlyOverruns) {
  const SerialCounters counters = some_counters();
  SerialCounters cleared;
  cleared.bus_comm_errors = 2;
  // 6.8.1 0x14: the echo of the request.
  EXPECT_EQ(ask({0x08, 0x00, 0x14, 0x00, 0x00}, counters, cleared),
            (Bytes{0x08, 0x00, 0x14, 0x00, 0x00}));
  SerialCounters want;
  want.bus_comm_errors = 2;
  want.bus_char_overruns = 9;
  EXPECT_TRUE(same(cleared, want));
  EXPECT_EQ(ask({0x08, 0x00, 0x12, 0x00, 0x00}, counters, cleared),
            (Bytes{0x08, 0x00, 0x12, 0x00, 0x00}));
  EXPECT_EQ(ask({0x08, 0x00, 0x0C, 0x00, 0x00}, counters, cleared),
            (Bytes{0x08, 0x00, 0x0C, 0x00, 0x0F}));  // 17 - 2
}

TEST(Diagnostics, UnknownSubFunctionIsIllegalFunction) {
  SerialCounters counters = some_counters(), cleared;
  // 01, 03, 04 (restart, ASCII delimiter, listen only) are not offered; 0x13 and 0x15 are not
  // served; others are not defined.
  for (const std::uint16_t sub :
       std::initializer_list<std::uint16_t>{0x0001, 0x0003, 0x0004, 0x0005, 0x0009, 0x0013, 0x0015,
                                            0x0016, 0x0100, 0x010B, 0xFFFF}) {
    SCOPED_TRACE(sub);
    EXPECT_EQ(
        ask({0x08, static_cast<std::uint8_t>(sub >> 8), static_cast<std::uint8_t>(sub), 0x00, 0x00},
            counters, cleared),
        (Bytes{0x88, 0x01}));
  }
  EXPECT_TRUE(same(cleared, SerialCounters{}));
}

TEST(Diagnostics, DataOtherThan0000IsIllegalDataValue) {
  const SerialCounters counters = some_counters();
  SerialCounters cleared;
  for (const std::uint8_t sub : std::initializer_list<std::uint8_t>{
           0x02, 0x0A, 0x0B, 0x0C, 0x0D, 0x0E, 0x0F, 0x10, 0x11, 0x12, 0x14}) {
    SCOPED_TRACE(static_cast<int>(sub));
    for (const Bytes& data : {Bytes{0x00, 0x01}, Bytes{0x01, 0x00}, Bytes{0xFF, 0x00},
                              Bytes{0x00, 0x00, 0x00}, Bytes{0x00, 0x00, 0x00, 0x00}}) {
      Bytes request{0x08, 0x00, sub};
      request.insert(request.end(), data.begin(), data.end());
      EXPECT_EQ(ask(request, counters, cleared), (Bytes{0x88, 0x03}));
    }
  }
  // A refused clear clears nothing.
  EXPECT_TRUE(same(cleared, SerialCounters{}));
}

TEST(Diagnostics, ShortRequestIsIllegalDataValue) {
  SerialCounters counters = some_counters(), cleared;
  for (const Bytes& request :
       {Bytes{}, Bytes{0x08}, Bytes{0x08, 0x00}, Bytes{0x08, 0x00, 0x00}, Bytes{0x08, 0x00, 0x0B},
        Bytes{0x08, 0x00, 0x0A, 0x00}, Bytes{0x08, 0x00, 0x00, 0xA5}}) {
    SCOPED_TRACE(request.size());
    EXPECT_EQ(ask(request, counters, cleared), (Bytes{0x88, 0x03}));
  }
  EXPECT_TRUE(same(cleared, SerialCounters{}));
}

}  // namespace
}  // namespace drivegate::modbus
