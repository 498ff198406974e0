// Telnet framing and RFC 2217 COM-PORT-OPTION messages, as golden bytes. Sections cited are of
// RFC 854 (Telnet), RFC 855 (options), RFC 2217 (Com Port Control Option).
#include "transport/telnet_codec.h"

#include <gtest/gtest.h>

namespace drivegate {
namespace {

using telnet::Event;

TEST(Telnet, DataFFIsDoubledOnTheWire_RFC854) {
  Bytes out;
  telnet::escape(Bytes{0x01, 0xFF, 0x02, 0xFF, 0xFF}, out);
  EXPECT_EQ(out, (Bytes{0x01, 0xFF, 0xFF, 0x02, 0xFF, 0xFF, 0xFF, 0xFF}));
}

TEST(Telnet, NegotiationAndSubnegotiationBytes_RFC855) {
  EXPECT_EQ(telnet::negotiation(telnet::kWill, telnet::kComPortOption), (Bytes{255, 251, 44}));
  // A payload 0xFF is doubled inside SB ... SE too.
  EXPECT_EQ(telnet::subnegotiation(44, Bytes{1, 0xFF}),
            (Bytes{255, 250, 44, 1, 255, 255, 255, 240}));
}

TEST(Telnet, DecoderSeparatesDataFromCommandsWhereverTheChunksSplit) {
  // clang-format off: one wire element a line
  const Bytes wire{0x10, 0xFF, 0xFF, 0x11,  // data 10 FF 11
                   255,  253,  44,          // DO COM-PORT-OPTION
                   0x12,                    // data 12
                   255,  250,  44,   101,  0,   0,   0x4B, 0,
                   255,  240,                                    // SB 44 101 (baud 19200) SE
                   255,  250,  44,   102,  255, 255, 255,  240,  // SB 44 102 FF(escaped) SE
                   255,  241,                                    // NOP: ignored
                   0x13};
  // clang-format on
  const Bytes data{0x10, 0xFF, 0x11, 0x12, 0x13};
  const std::vector<Event> events{
      {Event::Kind::negotiation, telnet::kDo, 44, {}},
      {Event::Kind::subnegotiation, 0, 44, {101, 0, 0, 0x4B, 0}},
      {Event::Kind::subnegotiation, 0, 44, {102, 0xFF}},
  };
  for (std::size_t cut = 0; cut <= wire.size(); ++cut) {
    telnet::Decoder d;
    Bytes got;
    std::vector<Event> ev;
    d.feed(ByteView(wire.data(), cut), got, ev);
    d.feed(ByteView(wire.data() + cut, wire.size() - cut), got, ev);
    EXPECT_EQ(got, data) << "cut at " << cut;
    EXPECT_EQ(ev, events) << "cut at " << cut;
  }
}

TEST(Telnet, AnEndlessSubnegotiationIsBoundedAndTheStreamRecovers) {
  telnet::Decoder d;
  Bytes data;
  std::vector<Event> ev;
  Bytes wire{255, 250, 44};
  wire.insert(wire.end(), 10'000, 0x42);
  wire.insert(wire.end(), {255, 240, 0x07});
  d.feed(wire, data, ev);
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_LE(ev[0].payload.size(), 64u);
  EXPECT_EQ(data, Bytes{0x07});
}

// RFC 2217, "Com Port Configuration Commands": SET-BAUDRATE 1 (4 bytes, network order),
// SET-DATASIZE 2, SET-PARITY 3 (1 NONE, 2 ODD, 3 EVEN), SET-STOPSIZE 4 (1 one, 2 two),
// SET-CONTROL 5 (1 no flow control).
TEST(Rfc2217, ConfigureAsksForEverySettingInItsOwnSubnegotiation) {
  const Bytes got = rfc2217::configure({19200, 8, Parity::even, 1});
  // clang-format off: one subnegotiation a line
  const Bytes want{255, 250, 44,  1,   0x00, 0x00, 0x4B, 0x00, 255, 240, 255, 250, 44,
                   2,   8,   255, 240, 255,  250,  44,   3,    3,   255, 240, 255, 250,
                   44,  4,   1,   255, 240,  255,  250,  44,   5,   1,   255, 240};
  // clang-format on
  EXPECT_EQ(got, want);
  EXPECT_EQ(rfc2217::parity_code(Parity::odd), 2);
  EXPECT_EQ(rfc2217::stop_code(2), 2);
}

TEST(Rfc2217, ABaudRateWithAnFFByteIsEscaped) {
  // 0x0001FFFF would put two 0xFF in the value: each is doubled.
  const Bytes got = rfc2217::configure({0x0001FFFF, 8, Parity::none, 1});
  EXPECT_EQ(Bytes(got.begin(), got.begin() + 12),
            (Bytes{255, 250, 44, 1, 0x00, 0x01, 0xFF, 0xFF, 0xFF, 0xFF, 255, 240}));
}

TEST(Rfc2217, TheServersAnswersAreCheckedAgainstWhatWasAsked) {
  const rfc2217::LineSettings asked{19200, 8, Parity::even, 1};
  rfc2217::ServerSettings s;
  EXPECT_TRUE(rfc2217::take_answer(Bytes{101, 0, 0, 0x4B, 0}, s));
  EXPECT_TRUE(rfc2217::take_answer(Bytes{102, 8}, s));
  EXPECT_TRUE(rfc2217::take_answer(Bytes{103, 3}, s));
  EXPECT_FALSE(s.complete());
  EXPECT_FALSE(rfc2217::take_answer(Bytes{106, 0x60}, s));  // NOTIFY-LINESTATE: not an answer
  EXPECT_FALSE(rfc2217::take_answer(Bytes{101, 0, 0}, s));  // short: ignored
  EXPECT_TRUE(rfc2217::take_answer(Bytes{104, 1}, s));
  EXPECT_TRUE(s.complete());
  EXPECT_EQ(rfc2217::mismatch(asked, s), "");
  rfc2217::take_answer(Bytes{101, 0, 0, 0x25, 0x80}, s);  // the server kept 9600
  rfc2217::take_answer(Bytes{103, 1}, s);
  EXPECT_EQ(rfc2217::mismatch(asked, s), "baud 9600 instead of 19200, parity code 1 instead of 3");
}

}  // namespace
}  // namespace drivegate
