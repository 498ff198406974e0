// The codec driven by the shipped descriptions: every golden vector of the vendor documents
// (shared/specs/README.md) and of the C++ adapters' own tables encodes and decodes exactly, whole
// and split at every byte; and damaged frames of every kind.
#include "codec.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "feed.h"
#include "protocol_fixture.h"

namespace drivegate::framed {
namespace {

using test::hex;
using test::Protocol;

// Decodes `wire` whole and split at every byte; every way must give the same frame.
void expect_decodes(const Protocol& p, Direction dir, const Bytes& wire, const std::string& name) {
  for (std::size_t split = 0; split <= wire.size(); ++split) {
    const auto d = drivegate::test::feed_split<Frame>(
        wire, split, [&](ByteView rx) { return p.decode(dir, Bytes(rx.begin(), rx.end())); });
    ASSERT_EQ(d.status, DecodeStatus::frame) << name << " split at " << split;
    EXPECT_EQ(d.consumed, wire.size()) << name;
    EXPECT_EQ(p.name_of(d), name);
  }
}

// ---- nidec-washer (000, V07) ---------------------------------------------------------------

class NidecVectors : public ::testing::Test {
 protected:
  Protocol p{"nidec-washer"};
};

TEST_F(NidecVectors, TheSpecsReadmeVectors) {
  // shared/specs/README.md, nidec-washer: poll, stop, FCT, CW 800 rpm 3.0 s, and the NACK.
  EXPECT_EQ(p.encode("request"), hex("A5 05 00 00 00 00 00 00 00 00 A0"));
  EXPECT_EQ(p.encode("stop"), hex("A5 27 00 00 00 00 00 00 00 00 82"));
  EXPECT_EQ(p.encode("fct_test"), hex("A5 66 12 00 34 00 56 00 78 00 CB"));
  EXPECT_EQ(p.encode("cw", {{"speed", 800}, {"accel_time", 30}}),
            hex("A5 09 03 20 00 1E 00 00 00 00 91"));
  expect_decodes(p, Direction::reply, hex("5A 00 FF 00 FF 00 5A"), "nack");
  for (const char* m : {"request", "stop", "fct_test"}) {
    expect_decodes(p, Direction::request, p.encode(m), m);
  }
  const auto cw = p.decode(Direction::request, hex("A5 09 03 20 00 1E 00 00 00 00 91"));
  EXPECT_EQ(p.name_of(cw), "cw");
  EXPECT_EQ(p.field(cw, "speed"), 800);
  EXPECT_EQ(p.field(cw, "accel_time"), 30);
}

TEST_F(NidecVectors, TheCppAdaptersOwnTable) {
  // adapters/nidec-washer/README.md, "Golden vectors": the same bytes from the description.
  EXPECT_EQ(p.encode("ping", {{"platform", 7}}), hex("A5 02 07 00 00 00 00 00 00 00 A0"));
  EXPECT_EQ(p.encode("ping", {{"platform", 7}, {"empty_raw_weight", 0x012C}}),
            hex("A5 02 07 01 2C 00 00 00 00 00 8D"));
  EXPECT_EQ(p.encode("ccw", {{"speed", 800}, {"accel_time", 30}}),
            hex("A5 0B 03 20 00 1E 00 00 00 00 93"));
  EXPECT_EQ(p.encode("agitation", {{"speed", 60},
                                   {"agitation_accel", 5},
                                   {"agitation_decel", 5},
                                   {"agitation_cw_on", 12},
                                   {"agitation_cw_off", 8},
                                   {"agitation_ccw_on", 12},
                                   {"agitation_ccw_off", 8}}),
            hex("A5 0C 00 3C 05 05 0C 08 0C 08 95"));
  EXPECT_EQ(p.encode("spin", {{"speed", 1200}, {"accel_time", 30}}),
            hex("A5 0D 04 B0 00 1E 00 00 00 00 02"));
  EXPECT_EQ(p.encode("brake"), hex("A5 29 00 00 00 00 00 00 00 00 8C"));
  EXPECT_EQ(p.encode("voltage_detection"), hex("A5 2B 00 00 00 00 00 00 00 00 8E"));
  EXPECT_EQ(p.encode("weight_detection"), hex("A5 2C 00 00 00 00 00 00 00 00 89"));
  EXPECT_EQ(p.encode("fabric_detection"), hex("A5 2D 00 00 00 00 00 00 00 00 88"));
  EXPECT_EQ(p.encode("forced_brake_enable"), hex("A5 1B 01 00 00 00 00 00 00 00 BF"));
  EXPECT_EQ(p.encode("forced_brake_disable"), hex("A5 1B 00 00 00 00 00 00 00 00 BE"));
  EXPECT_EQ(p.encode("free_shaft_spin", {{"speed", 1500}, {"accel_time", 50}}),
            hex("A5 1D 05 DC 00 32 00 00 00 00 53"));

  const auto request_ack = hex("A5 05 00 03 20 23 A0");  // 800 rpm, 3.5 kg
  expect_decodes(p, Direction::reply, request_ack, "request_ack");
  auto d = p.decode(Direction::reply, request_ack);
  EXPECT_EQ(p.field(d, "error"), 0);
  EXPECT_EQ(p.field(d, "speed"), 800);
  EXPECT_EQ(p.field(d, "weight"), 35);
  d = p.decode(Direction::reply, hex("A5 02 07 01 07 00 A6"));  // ping ACK, version 0x0107
  EXPECT_EQ(p.name_of(d), "ping_ack");
  EXPECT_EQ(p.field(d, "platform"), 7);
  EXPECT_EQ(p.field(d, "inverter_version"), 0x0107);
  d = p.decode(Direction::reply, hex("A5 09 08 03 20 00 87"));  // CW ACK with stall 0x08
  EXPECT_EQ(p.name_of(d), "cw_ack");
  EXPECT_EQ(p.field(d, "error"), 0x08);
  d = p.decode(Direction::reply, hex("A5 2B 00 01 37 00 B8"));  // voltage ACK 311 V
  EXPECT_EQ(p.field(d, "dc_bus_voltage"), 311);
  d = p.decode(Direction::reply, hex("A5 2C 00 05 1C 23 B3"));  // weight ACK raw 1308, 3.5 kg
  EXPECT_EQ(p.field(d, "raw_weight"), 1308);
  EXPECT_EQ(p.field(d, "weight"), 35);
  const auto fct = hex("A5 66 00 08 00 00 00 2D 11 37 00 00 C0");  // FCT ACK, 13 bytes
  expect_decodes(p, Direction::reply, fct, "fct_ack");
  d = p.decode(Direction::reply, fct);
  EXPECT_EQ(p.field(d, "fct_error"), 8);
  EXPECT_EQ(p.field(d, "fct_ipm_temperature"), 0x2D);
  EXPECT_EQ(p.field(d, "fct_ipm_model_bus_volt_high"), 0x11);
  EXPECT_EQ(p.field(d, "fct_bus_volt_low"), 0x37);
}

TEST_F(NidecVectors, DamagedFramesAreDroppedUpToTheNextFrameStart) {
  // A bad XOR: the whole run when no frame starts inside it.
  auto d = p.decode(Direction::reply, hex("A5 05 00 03 20 23 A1"));
  EXPECT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, make_error_code(FrameError::bad_checksum));
  EXPECT_EQ(d.consumed, 7u);
  // A lost byte: a good frame starts inside the damaged run, and is found.
  const Bytes cut = hex("A5 05 00 03 A5 05 00 03 20 23 A0");
  d = p.decode(Direction::reply, cut);
  EXPECT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, make_error_code(FrameError::bad_checksum));
  EXPECT_EQ(d.consumed, 4u);
  d = p.decode(Direction::reply, Bytes(cut.begin() + 4, cut.end()));
  EXPECT_EQ(p.name_of(d), "request_ack");
  // A byte that starts no frame; a mode V07 does not have (0x19, removed).
  d = p.decode(Direction::reply, hex("00 A5"));
  EXPECT_EQ(d.error, make_error_code(FrameError::bad_header));
  EXPECT_EQ(d.consumed, 1u);
  d = p.decode(Direction::reply, hex("A5 19 00 00 00 00 BC"));
  EXPECT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.consumed, 1u);
  // Incomplete until the frame is whole; a master's frame is not a reply.
  EXPECT_EQ(p.decode(Direction::reply, hex("A5 05 00")).status, DecodeStatus::incomplete);
  EXPECT_EQ(p.decode(Direction::reply, hex("A5 05 00 00 00 00 00 00 00 00 A0")).status,
            DecodeStatus::bad);
}

// ---- mdriver-2400 (002): src dst cmd n data cs, the sum of all bytes 0x55 -------------------

class MdriverVectors : public ::testing::Test {
 protected:
  Protocol p{"mdriver-2400"};
};

TEST_F(MdriverVectors, TheSpecsReadmeVectors) {
  // shared/specs/README.md: the fixed-code check and the run at 504 rpm (code 0x1C, normal).
  EXPECT_EQ(p.encode("check", {{"master", 0}, {"address", 1}}), hex("00 01 00 03 01 12 00 06 38"));
  EXPECT_EQ(p.encode("run", {{"master", 0}, {"address", 1}, {"code", 0x1C}, {"change", 0x01}}),
            hex("00 01 10 02 1C 01 00 25"));
  expect_decodes(p, Direction::request, hex("00 01 10 02 1C 01 00 25"), "run");
  // The length byte is data length - 1 (n = 02 for three data bytes), worked out on encoding.
  const auto run = p.decode(Direction::request, hex("00 01 10 02 1C 01 00 25"));
  EXPECT_EQ(p.field(run, "n"), 2);
  EXPECT_EQ(p.field(run, "code"), 0x1C);
}

TEST_F(MdriverVectors, TheCppAdaptersOwnTableAndEveryRowOfTheConversionTables) {
  // adapters/mdriver-2400/README.md, "Frames": the driver's echo, the fixed-code error, a reply.
  expect_decodes(p, Direction::reply, hex("01 00 00 03 01 12 00 06 38"), "check_reply");
  auto d = p.decode(Direction::reply, hex("01 00 00 03 00 00 00 00 51"));
  EXPECT_EQ(p.name_of(d), "check_reply");
  EXPECT_EQ(p.field(d, "code"), 0);
  const auto reply = hex("01 00 10 07 1C 1C 00 00 1A 00 00 00 EB");
  expect_decodes(p, Direction::reply, reply, "run_reply");
  d = p.decode(Direction::reply, reply);
  EXPECT_EQ(p.field(d, "target_code"), 0x1C);
  EXPECT_EQ(p.field(d, "ipm_temperature"), 26);
  // Both conversion tables: every row's checksum, normal (D5 = 01) and continuous (FF) mode.
  for (unsigned code = 0; code <= 0x9F; ++code) {
    for (const unsigned change : {0x01u, 0xFFu}) {
      const Bytes f =
          p.encode("run", {{"master", 0}, {"address", 1}, {"code", code}, {"change", change}});
      const auto want =
          static_cast<std::uint8_t>(0x55 - (0x00 + 0x01 + 0x10 + 0x02 + code + change));
      ASSERT_EQ(f.back(), want) << std::hex << code;
    }
  }
}

TEST_F(MdriverVectors, ALengthByteThatDoesNotFitIsNotTheFrame) {
  // n = 03 on a run: no layout holds three data bytes after it, so one byte is dropped.
  auto d = p.decode(Direction::reply, hex("01 00 10 03 1C 1C 00 00 1A 00 00 00 EA"));
  EXPECT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, make_error_code(FrameError::bad_length));
  EXPECT_EQ(d.consumed, 1u);
  // A bad sum drops the run.
  d = p.decode(Direction::reply, hex("01 00 10 07 1C 1C 00 00 1A 00 00 00 EC"));
  EXPECT_EQ(d.error, make_error_code(FrameError::bad_checksum));
}

// ---- fdc1 (003): the stream 27 76 b3 b4 b5 b6 co ce, decimal numbers ----------------------------

class Fdc1Vectors : public ::testing::Test {
 protected:
  Protocol p{"fdc1"};
};

TEST_F(Fdc1Vectors, TheSpecsReadmeAndTheCppAdaptersVectors) {
  // shared/specs/README.md: 2000..3000 rpm gives x = 10.
  EXPECT_EQ(p.encode("speed", {{"min", 2000}, {"max", 3000}}), hex("48 73 07 D0 0B B8 55 0A"));
  // adapters/fdc1/README.md, "Golden vectors".
  EXPECT_EQ(p.encode("speed", {{"min", 2000}, {"max", 2000}}), hex("48 73 07 D0 07 D0 55 6E"));
  EXPECT_EQ(p.encode("speed", {{"min", 0}, {"max", 3500}}), hex("48 73 00 00 0D AC 55 CF"));
  expect_decodes(p, Direction::reply, hex("1B 4C 09 C4 1E DC 0C 54"), "status_on");
  auto d = p.decode(Direction::reply, hex("1B 4C 09 C4 1E DC 0C 54"));  // ON, 2500 rpm, 2.5 A
  EXPECT_EQ(p.field(d, "rpm"), 2500);
  EXPECT_EQ(p.field(d, "current"), 7900);
  expect_decodes(p, Direction::reply, hex("1B 4C 00 30 04 C4 1F B8"), "status_off");
  d = p.decode(Direction::reply, hex("1B 4C 00 30 04 C4 1F B8"));  // OFF, alarm 48, 10 s
  EXPECT_EQ(p.field(d, "alarm_code"), 48);
  EXPECT_EQ(p.field(d, "restart"), 1220);
  expect_decodes(p, Direction::reply, hex("1B 4C 00 00 00 00 1B 4C"), "status_off");  // idle
  EXPECT_EQ(p.encode("status_on", {{"rpm", 2500}, {"current", 7900}}),
            hex("1B 4C 09 C4 1E DC 0C 54"));
}

TEST_F(Fdc1Vectors, TheStreamResynchronisesOnItsHeader) {
  // A byte lost inside a status: dropped up to the next 1B, which starts the next one.
  const Bytes wire = hex("1B 4C 09 C4 1E DC 0C 1B 4C 00 00 00 00 1B 4C");
  auto d = p.decode(Direction::reply, wire);
  EXPECT_EQ(d.error, make_error_code(FrameError::bad_checksum));
  EXPECT_EQ(d.consumed, 7u);
  d = p.decode(Direction::reply, Bytes(wire.begin() + 7, wire.end()));
  EXPECT_EQ(p.name_of(d), "status_off");
  // Noise before a header; a wrong second header byte.
  EXPECT_EQ(p.decode(Direction::reply, hex("00 FF 1B")).consumed, 1u);
  EXPECT_EQ(p.decode(Direction::reply, hex("1B 4D 00 00 00 00 1B 4D")).status, DecodeStatus::bad);
  // The master's own header is not the controller's.
  EXPECT_EQ(p.decode(Direction::reply, hex("48 73")).status, DecodeStatus::bad);
}

}  // namespace
}  // namespace drivegate::framed
