// The language's checks, encodings and framings on descriptions written here: every CRC by its
// parameters against its catalogue check value ("123456789"), LRC, two's complement, start / end
// flags with byte stuffing (the specs README's unicla vectors, CRC-16/XMODEM), a length field
// counting the payload, BCD, f32 in both orders, signed fields.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "codec.h"
#include "description_parser.h"
#include "feed.h"
#include "protocol_fixture.h"

namespace drivegate::framed::framed_checks_test {
namespace {

using test::hex;

std::shared_ptr<const Description> parsed(const std::string& body) {
  auto r = parse_description(
      "[protocol]\nname = \"t\"\nsummary = \"t\"\ndocument = \"t\"\n[line]\nbaud = 9600\n" + body,
      "t.toml");
  if (const auto* e = std::get_if<std::vector<std::string>>(&r)) {
    for (const auto& line : *e) ADD_FAILURE() << line;
    return nullptr;
  }
  return std::get<std::shared_ptr<const Description>>(r);
}

// A request message `name` of `layout`, as a description's [[message]].
std::string request(const std::string& name, const std::string& layout) {
  return "[[message]]\nname = \"" + name + "\"\ndirection = \"request\"\nlayout = \"" + layout +
         "\"\n";
}

// The bytes of message `m` from `values`, through the description's own codec.
Bytes encode(const Description& d, const std::string& m, std::vector<double> values = {}) {
  return Codec(d).encode(*d.message(m), values);
}

const std::string kDigits = "31 32 33 34 35 36 37 38 39";  // "123456789"

// CRC-16/MODBUS's parameters: Modbus RTU's CRC, sent low byte first.
const std::string kModbusCrc =
    "poly = 0x8005\ninit = 0xFFFF\nreflect_in = true\nreflect_out = true\norder = \"little\"\n";

// A CRC by its parameters (the keys of a [check] of kind "crc" but kind) and its catalogue check
// value, over "123456789", as the description sends it.
struct Crc {
  const char* name;
  std::string parameters;
  const char* check;
};

TEST(Checks, EveryCrcByItsParametersGivesItsCatalogueValue) {
  const Crc crcs[] = {
      {"CRC-8/SMBUS", "width = 1\npoly = 0x07\n", "F4"},
      {"CRC-16/XMODEM", "poly = 0x1021\n", "31 C3"},
      {"CRC-16/MODBUS", kModbusCrc, "37 4B"},  // 4B37, low byte first
      {"CRC-16/KERMIT",
       "poly = 0x1021\nreflect_in = true\nreflect_out = true\norder = \"little\"\n",
       "89 21"},  // 2189, reflected, low byte first
      {"CRC-32",
       "width = 4\npoly = 0x04C11DB7\ninit = 0xFFFFFFFF\nreflect_in = true\nreflect_out = true\n"
       "xor_out = 0xFFFFFFFF\n",
       "CB F4 39 26"},
      {"CRC-32/BZIP2", "width = 4\npoly = 0x04C11DB7\ninit = 0xFFFFFFFF\nxor_out = 0xFFFFFFFF\n",
       "FC 89 19 18"},
  };
  for (const Crc& c : crcs) {
    SCOPED_TRACE(c.name);
    const auto d =
        parsed("[check.c]\nkind = \"crc\"\n" + c.parameters + request("m", kDigits + " c:c"));
    ASSERT_NE(d, nullptr);
    EXPECT_EQ(encode(*d, "m"), hex(kDigits + " " + c.check));
  }
}

TEST(Checks, ModbusRtuLrcAndTwosComplement) {
  const auto d =
      parsed("[check.crc]\nkind = \"crc\"\n" + kModbusCrc + "[check.lrc]\nkind = \"lrc\"\n" +
             "[check.neg]\nkind = \"twos_complement\"\nwidth = 2\n" +
             request("write", "address:u8 06 register:u16 value:u16 crc:crc") +
             request("ascii", "01 03 00 00 00 0A lrc:lrc") + request("neg", "01 02 03 s:neg"));
  ASSERT_NE(d, nullptr);
  // shared/specs/README.md, ed3100: the stop write, Modbus RTU's CRC low byte first.
  EXPECT_EQ(encode(*d, "write", {0x1F, 0x2000, 0x0001}), hex("1F 06 20 00 00 01 40 74"));
  EXPECT_EQ(encode(*d, "ascii"), hex("01 03 00 00 00 0A F2"));  // MODBUS over Serial Line 6.2.1
  EXPECT_EQ(encode(*d, "neg"), hex("01 02 03 FF FA"));
}

const std::string kFlagged = R"(
[framing]
start = 0x7E
end = 0x7E
escape = 0x7D
escaped = [0x7E, 0x7D]
escape_xor = 0x20
max_frame = 32
[check.crc]
kind = "crc"
poly = 0x1021
[frame.out]
layout = "src:u8 dst:u8 {body} crc:crc"
length = { field = "n", counts = "payload" }
[[message]]
name = "read_status"
direction = "request"
frame = "out"
body = "C0 01 seq:u8 00 00 n:u8"
[[message]]
name = "set_run_state"
direction = "request"
frame = "out"
body = "C1 C0 seq:u8 00 00 n:u8 speed:u16"
)";

TEST(Framings, FlagsStuffingAndALengthCountingThePayload) {
  const auto d = parsed(kFlagged);
  ASSERT_NE(d, nullptr);
  // shared/specs/README.md, unicla-edrive: 00 01 C0 01 36 00 00 00 -> CRC A7 70, flagged.
  const Bytes read = hex("7E 00 01 C0 01 36 00 00 00 A7 70 7E");
  EXPECT_EQ(encode(*d, "read_status", {0x00, 0x01, 0x36}), read);
  // Its set run state example: speed 1000 = 03 E8, payload size 2.
  const Bytes set = hex("7E 00 01 C1 C0 36 00 00 02 03 E8 34 CC 7E");
  EXPECT_EQ(encode(*d, "set_run_state", {0x00, 0x01, 0x36, 0, 1000}), set);
  const Codec codec(*d);
  for (const Bytes& wire : {read, set}) {
    for (std::size_t split = 0; split <= wire.size(); ++split) {
      const auto got = drivegate::test::feed_split<Frame>(
          wire, split, [&](ByteView rx) { return codec.decode(Direction::request, rx); });
      ASSERT_EQ(got.status, DecodeStatus::frame) << split;
      EXPECT_EQ(got.consumed, wire.size());
    }
  }
  // A flag and an escape inside the frame are sent escaped: 7E -> 7D 5E, 7D -> 7D 5D.
  const Bytes stuffed = encode(*d, "read_status", {0x7D, 0x01, 0x7E});
  EXPECT_EQ(Bytes(stuffed.begin(), stuffed.begin() + 8), hex("7E 7D 5D 01 C0 01 7D 5E"));
  for (std::size_t i = 1; i + 1 < stuffed.size(); ++i) EXPECT_NE(stuffed[i], 0x7E) << i;
  const auto back = codec.decode(Direction::request, stuffed);
  ASSERT_EQ(back.status, DecodeStatus::frame);
  EXPECT_EQ(codec.value(back.frame, 0), 0x7D);
  EXPECT_EQ(codec.value(back.frame, 2), 0x7E);
}

TEST(Framings, DamagedFlaggedFramesCostOneFrameNotTheNext) {
  const auto d = parsed(kFlagged);
  ASSERT_NE(d, nullptr);
  const Codec codec(*d);
  // Noise before a start flag: dropped up to it.
  auto r = codec.decode(Direction::request, hex("11 22 7E"));
  EXPECT_EQ(r.error, make_error_code(FrameError::bad_header));
  EXPECT_EQ(r.consumed, 2u);
  // A bad CRC: dropped up to the end flag, which may open the next frame.
  r = codec.decode(Direction::request, hex("7E 00 01 C0 01 36 00 00 00 A7 71 7E"));
  EXPECT_EQ(r.error, make_error_code(FrameError::bad_checksum));
  EXPECT_EQ(r.consumed, 11u);
  // An escape that escapes nothing the framing stuffs.
  r = codec.decode(Direction::request, hex("7E 00 7D 11 7E"));
  EXPECT_EQ(r.error, make_error_code(FrameError::bad_escape));
  // Two flags: an end and a start; a payload size that does not fit.
  EXPECT_EQ(codec.decode(Direction::request, hex("7E 7E")).consumed, 1u);
  r = codec.decode(Direction::request, hex("7E 00 01 C0 01 36 00 00 05 A7 70 7E"));
  EXPECT_EQ(r.status, DecodeStatus::bad);
  // No end flag yet: incomplete, until longer than the longest frame.
  EXPECT_EQ(codec.decode(Direction::request, hex("7E 00 01")).status, DecodeStatus::incomplete);
  EXPECT_EQ(codec.decode(Direction::request, Bytes(40, 0x01)).status, DecodeStatus::bad);
}

TEST(Encodings, BcdFloatsAndSignedInEitherOrder) {
  const auto d = parsed("[check.x]\nkind = \"xor\"\n" +
                        request("m", "AA b:bcd2 f:f32 g:f32le s:i16 t:i16le u:u24 x:x"));
  ASSERT_NE(d, nullptr);
  const Bytes wire = encode(*d, "m", {1234, 1.5, 1.5, -2, -2, 0x123456});
  ASSERT_EQ(wire.size(), 19u);
  EXPECT_EQ(Bytes(wire.begin(), wire.end() - 1),
            hex("AA 12 34 3F C0 00 00 00 00 C0 3F FF FE FE FF 12 34 56"));
  const Codec codec(*d);
  const auto r = codec.decode(Direction::request, wire);
  ASSERT_EQ(r.status, DecodeStatus::frame);
  std::array<double, kMaxFields> v{};
  codec.values(r.frame, v);
  EXPECT_EQ(v[0], 1234);
  EXPECT_EQ(v[1], 1.5);
  EXPECT_EQ(v[2], 1.5);
  EXPECT_EQ(v[3], -2);
  EXPECT_EQ(v[4], -2);
  EXPECT_EQ(v[5], 0x123456);
  // A nibble over 9 is not BCD: not this message.
  Bytes bad = wire;
  ASSERT_GT(bad.size(), 2u);
  bad.at(1) = 0x1A;
  bad.back() = 0;
  for (std::size_t i = 0; i + 1 < bad.size(); ++i) bad.back() ^= bad[i];
  EXPECT_EQ(codec.decode(Direction::request, bad).status, DecodeStatus::bad);
}

}  // namespace
}  // namespace drivegate::framed::framed_checks_test
