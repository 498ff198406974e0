// The Modbus serial codec against frames published by others: the request and reply examples of
// the Simply Modbus pages ("Function 01 / 03 / 05 / 06 / 16", simplymodbus.ca), whose PDUs are
// those of the Application Protocol's examples with slave address 0x11, and whose CRCs were not
// computed here. Everything is decoded whole and split at every byte.
#include "codec.h"

#include <gtest/gtest.h>

#include <optional>
#include <string>

#include "drivegate/crc.h"
#include "feed.h"

namespace drivegate::modbus_device {
namespace {

using drivegate::test::Buffer;
using drivegate::test::feed_split;

Buffer bytes_of(std::string_view text) {
  return {text.begin(), text.end()};
}

// Simply Modbus, "Function 03": read holding registers 40108..40110 of slave 17.
const Buffer kReadHolding = {0x11, 0x03, 0x00, 0x6B, 0x00, 0x03, 0x76, 0x87};
const Buffer kReadHoldingReply = {0x11, 0x03, 0x06, 0xAE, 0x41, 0x56, 0x52, 0x43, 0x40, 0x49, 0xAD};
// "Function 01": read coils 00020..00056.
const Buffer kReadCoils = {0x11, 0x01, 0x00, 0x13, 0x00, 0x25, 0x0E, 0x84};
// "Function 05": coil 00173 ON; the reply is the request echoed.
const Buffer kWriteCoil = {0x11, 0x05, 0x00, 0xAC, 0xFF, 0x00, 0x4E, 0x8B};
// "Function 06": register 40002 = 3; echoed.
const Buffer kWriteRegister = {0x11, 0x06, 0x00, 0x01, 0x00, 0x03, 0x9A, 0x9B};
// "Function 16": registers 40002..40003 = 0x000A, 0x0102.
const Buffer kWriteRegisters = {0x11, 0x10, 0x00, 0x01, 0x00, 0x02, 0x04,
                                0x00, 0x0A, 0x01, 0x02, 0xC6, 0xF0};
// decode_reply and decode_request with no code of known layout, as values
// expect_frame_everywhere can take.
const auto reply = [](Framing framing, ByteView rx) { return decode_reply(framing, rx); };
const auto request_of = [](Framing framing, ByteView rx) { return decode_request(framing, rx); };
// The "Function 03" request in ASCII (Simply Modbus, "Modbus ASCII"): LRC 0x7E.
const std::string_view kReadHoldingAscii = ":1103006B00037E\r\n";

Buffer pdu_of(const Buffer& rtu) {
  return {rtu.begin() + 1, rtu.end() - 2};
}

template <typename Decode>
void expect_frame_everywhere(Decode decode, Framing framing, const Buffer& wire,
                             std::uint8_t address, const Buffer& pdu) {
  for (std::size_t split = 0; split <= wire.size(); ++split) {
    const auto d = feed_split<Adu>(wire, split, [&](ByteView rx) { return decode(framing, rx); });
    ASSERT_EQ(d.status, DecodeStatus::frame) << "split " << split;
    EXPECT_EQ(d.consumed, wire.size()) << "split " << split;
    EXPECT_EQ(d.frame.address, address);
    EXPECT_EQ(d.frame.pdu, pdu);
  }
}

TEST(ModbusCodec, CrcOfThePublishedFrames) {
  for (const Buffer* f : {&kReadHolding, &kReadHoldingReply, &kReadCoils, &kWriteCoil,
                          &kWriteRegister, &kWriteRegisters}) {
    const std::uint16_t c = crc16_modbus(ByteView(*f).first(f->size() - 2));
    EXPECT_EQ(lo8(c), (*f)[f->size() - 2]);  // low byte first (Serial Line 6.2.2)
    EXPECT_EQ(hi8(c), (*f)[f->size() - 1]);
  }
}

TEST(ModbusCodec, EncodesThePublishedRequestsInRtu) {
  for (const Buffer* f :
       {&kReadHolding, &kReadCoils, &kWriteCoil, &kWriteRegister, &kWriteRegisters}) {
    EXPECT_EQ(encode(Framing::rtu, 0x11, pdu_of(*f)), *f);
  }
}

TEST(ModbusCodec, EncodesThePublishedRequestInAscii) {
  EXPECT_EQ(encode(Framing::ascii, 0x11, pdu_of(kReadHolding)), bytes_of(kReadHoldingAscii));
  EXPECT_EQ(lrc(Buffer{0x11, 0x03, 0x00, 0x6B, 0x00, 0x03}), 0x7E);
}

TEST(ModbusCodec, ASlaveDecodesEachRequestWholeAndSplit) {
  for (const Buffer* f :
       {&kReadHolding, &kReadCoils, &kWriteCoil, &kWriteRegister, &kWriteRegisters}) {
    expect_frame_everywhere(request_of, Framing::rtu, *f, 0x11, pdu_of(*f));
  }
  expect_frame_everywhere(request_of, Framing::ascii, bytes_of(kReadHoldingAscii), 0x11,
                          pdu_of(kReadHolding));
}

TEST(ModbusCodec, AMasterDecodesEachReplyWholeAndSplit) {
  // 03 by its byte count; 05, 06 and 16 are 8 bytes (Application Protocol 6.5, 6.6, 6.12).
  expect_frame_everywhere(reply, Framing::rtu, kReadHoldingReply, 0x11, pdu_of(kReadHoldingReply));
  expect_frame_everywhere(reply, Framing::rtu, kWriteCoil, 0x11, pdu_of(kWriteCoil));
  expect_frame_everywhere(reply, Framing::rtu, kWriteRegister, 0x11, pdu_of(kWriteRegister));
  const Buffer written = encode(Framing::rtu, 0x11, Buffer{0x10, 0x00, 0x01, 0x00, 0x02});
  expect_frame_everywhere(reply, Framing::rtu, written, 0x11, Buffer{0x10, 0x00, 0x01, 0x00, 0x02});
  const Buffer ascii = encode(Framing::ascii, 0x11, pdu_of(kReadHoldingReply));
  EXPECT_EQ(ascii, bytes_of(":110306AE4156524340CC\r\n"));  // LRC: 0x100 - (0x234 & 0xFF)
  expect_frame_everywhere(reply, Framing::ascii, ascii, 0x11, pdu_of(kReadHoldingReply));
}

TEST(ModbusCodec, ExceptionRepliesAreFiveBytesAndNameTheirCode) {
  const Buffer pdu = exception_pdu(0x03, 0x02);
  EXPECT_EQ(pdu, (Buffer{0x83, 0x02}));
  const Buffer wire = encode(Framing::rtu, 0x11, pdu);
  ASSERT_EQ(wire.size(), 5u);
  expect_frame_everywhere(reply, Framing::rtu, wire, 0x11, pdu);
  EXPECT_EQ(exception_code(pdu), 0x02);
  EXPECT_EQ(exception_code(pdu_of(kReadHoldingReply)), std::nullopt);
}

TEST(ModbusCodec, AReplyOfAnUnknownFunctionEndsWhereItsCrcHolds) {
  // 0x41 is in the user-defined range (Application Protocol 5).
  const Buffer pdu = {0x41, 0x01, 0x02, 0x03, 0x04, 0x05};
  const Buffer wire = encode(Framing::rtu, 0x05, pdu);
  expect_frame_everywhere(reply, Framing::rtu, wire, 0x05, pdu);
  // 256 bytes with no CRC anywhere: a bad frame, not a buffer that grows for ever.
  Buffer junk(256, 0x00);
  junk[0] = 0x05;
  junk[1] = 0x41;
  for (std::size_t i = 2; i < junk.size(); ++i) junk[i] = static_cast<std::uint8_t>(i * 7);
  bool found_crc = false;
  for (std::size_t n = 4; n <= junk.size(); ++n) {
    if (crc16_modbus(ByteView(junk).first(n - 2)) == be16(junk[n - 1], junk[n - 2]))
      found_crc = true;
  }
  ASSERT_FALSE(found_crc) << "the junk must hold no CRC for this test to mean anything";
  const auto d = decode_reply(Framing::rtu, junk);
  EXPECT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.consumed, 256u);
}

// An inverter's "write without saving" 0x41 has 0x06's layout (V&T E5-H manual p.116: "Function
// 0x06(0x41) rewrites single function code or control parameter"). Its echo ends where 0x06's does:
// found by its CRC alone, an echo whose first bytes happen to end in a good CRC would be cut short
// and the rest taken for noise, the write answered as if the drive had not taken it.
TEST(ModbusCodec, AUserCodeOfKnownLayoutEndsWhereThatLayoutSays) {
  const CodeLayout like06[] = {{0x41, fc::write_single_register}};
  std::optional<Buffer> early;  // an echo of 0x8001 holding a good CRC before its end
  for (std::uint32_t value = 0; value <= 0xFFFF && !early; ++value) {
    const Buffer pdu = {0x41, 0x80, 0x01, static_cast<std::uint8_t>(value >> 8),
                        static_cast<std::uint8_t>(value & 0xFF)};
    const Buffer wire = encode(Framing::rtu, 0x01, pdu);
    if (crc_end(wire) != wire.size()) early = wire;
  }
  ASSERT_TRUE(early)
      << "some value's echo must end early by its CRC for this test to mean anything";
  const auto by_crc = decode_reply(Framing::rtu, *early);
  ASSERT_EQ(by_crc.status, DecodeStatus::frame);
  EXPECT_LT(by_crc.consumed, early->size());
  const Buffer pdu(early->begin() + 1, early->end() - 2);
  const auto laid_out = [&](Framing f, ByteView rx) { return decode_reply(f, rx, like06); };
  const auto whole = [&](ByteView rx) { return laid_out(Framing::rtu, rx); };
  expect_frame_everywhere(laid_out, Framing::rtu, *early, 0x01, pdu);
  EXPECT_EQ(whole(*early).consumed, 8u);
  // Its exception, 0xC1, is five bytes as every exception is; the public code's echo and
  // exception (a drive that answers 0x41 with 0x06) keep their own lengths.
  const Buffer refused = encode(Framing::rtu, 0x01, Buffer{0xC1, 0x04});
  EXPECT_EQ(whole(refused).consumed, 5u);
  const Buffer as06 = encode(Framing::rtu, 0x01, Buffer{0x06, 0x80, 0x01, 0x13, 0x88});
  EXPECT_EQ(whole(as06).consumed, 8u);
  // 0x42 laid out as 0x10: address and quantity echoed.
  const CodeLayout like10[] = {{0x42, fc::write_multiple_registers}};
  const Buffer multi = encode(Framing::rtu, 0x01, Buffer{0x42, 0x80, 0x00, 0x00, 0x02});
  EXPECT_EQ(decode_reply(Framing::rtu, multi, like10).consumed, 8u);
  // A slave finds the request's end the same way: 0x41's request is 0x06's, 0x42's is 0x10's.
  EXPECT_EQ(decode_request(Framing::rtu, *early, like06).consumed, 8u);
  const Buffer request10 =
      encode(Framing::rtu, 0x01, Buffer{0x42, 0x80, 0x00, 0x00, 0x02, 0x04, 0, 1, 0, 2});
  EXPECT_EQ(decode_request(Framing::rtu, request10, like10).consumed, request10.size());
}

TEST(ModbusCodec, DeviceIdentificationRepliesAreWalkedObjectByObject) {
  // Application Protocol 6.21: basic identification, three objects, all in one reply.
  const Buffer pdu = {0x2B, 0x0E, 0x01, 0x01, 0x00, 0x00, 0x03,  // 01: basic; 3 objects
                      0x00, 0x03, 'A',  'B',  'B',               // VendorName
                      0x01, 0x04, 'A',  'C',  'S',  '5',         // ProductCode
                      0x02, 0x02, '1',  '0'};                    // MajorMinorRevision
  expect_frame_everywhere(reply, Framing::rtu, encode(Framing::rtu, 0x07, pdu), 0x07, pdu);
  const Buffer request = {0x2B, 0x0E, 0x01, 0x00};
  expect_frame_everywhere(request_of, Framing::rtu, encode(Framing::rtu, 0x07, request), 0x07,
                          request);
}

TEST(ModbusCodec, ReadFifoRepliesCarryATwoByteCount) {
  // Application Protocol 6.18: byte count 6 = FIFO count (2) + two registers.
  const Buffer pdu = {0x18, 0x00, 0x06, 0x00, 0x02, 0x01, 0xB8, 0x12, 0x84};
  expect_frame_everywhere(reply, Framing::rtu, encode(Framing::rtu, 0x11, pdu), 0x11, pdu);
}

TEST(ModbusCodec, ABadCrcCostsTheWholeFrame) {
  Buffer wire = kReadHoldingReply;
  wire[4] ^= 0x01;
  const auto d = decode_reply(Framing::rtu, wire);
  EXPECT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, make_error_code(FrameError::bad_checksum));
  EXPECT_EQ(d.consumed, wire.size());
}

TEST(ModbusCodec, AReservedAddressIsNoiseOneByteAtATime) {
  // Serial Line 2.2: 248..255 are reserved; such a byte cannot start a frame.
  Buffer wire = {0xF8};
  wire.insert(wire.end(), kReadHoldingReply.begin(), kReadHoldingReply.end());
  const auto d = decode_reply(Framing::rtu, wire);
  EXPECT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, make_error_code(FrameError::bad_header));
  EXPECT_EQ(d.consumed, 1u);
  const auto next = decode_reply(Framing::rtu, ByteView(wire).subspan(1));
  EXPECT_EQ(next.status, DecodeStatus::frame);
}

TEST(ModbusCodec, AByteCountBeyondTheLongestFrameIsBad) {
  // A read reply claiming 252 data bytes would be 257 bytes: longer than RTU allows (256).
  const Buffer wire = {0x11, 0x03, 0xFC};
  const auto d = decode_reply(Framing::rtu, wire);
  EXPECT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, make_error_code(FrameError::bad_length));
}

TEST(ModbusCodec, AsciiSkipsNoiseToTheColonAndChecksEveryCharacter) {
  const Buffer noisy = bytes_of("xx:1103006B00037E\r\n");
  const auto skip = decode_request(Framing::ascii, noisy);
  EXPECT_EQ(skip.status, DecodeStatus::bad);
  EXPECT_EQ(skip.error, make_error_code(FrameError::bad_header));
  EXPECT_EQ(skip.consumed, 2u);

  // Lower case hex is read too.
  EXPECT_EQ(decode_request(Framing::ascii, bytes_of(":1103006b00037e\r\n")).status,
            DecodeStatus::frame);

  const auto lrc_wrong = decode_request(Framing::ascii, bytes_of(":1103006B00037F\r\n"));
  EXPECT_EQ(lrc_wrong.error, make_error_code(FrameError::bad_checksum));
  EXPECT_EQ(lrc_wrong.consumed, kReadHoldingAscii.size());

  const auto not_hex = decode_request(Framing::ascii, bytes_of(":1103006G00037E\r\n"));
  EXPECT_EQ(not_hex.error, make_error_code(FrameError::bad_field));

  const auto no_cr = decode_request(Framing::ascii, bytes_of(":1103006B00037E\n"));
  EXPECT_EQ(no_cr.error, make_error_code(FrameError::bad_field));

  const auto odd = decode_request(Framing::ascii, bytes_of(":1103006B00037\r\n"));
  EXPECT_EQ(odd.error, make_error_code(FrameError::bad_length));

  // A ':' before CR LF starts a new message: the one before it was cut short (2.5.2.1).
  const Buffer cut = bytes_of(":1103006B:1103006B00037E\r\n");
  const auto d = decode_request(Framing::ascii, cut);
  EXPECT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.consumed, 9u);
  EXPECT_EQ(decode_request(Framing::ascii, ByteView(cut).subspan(9)).status, DecodeStatus::frame);
}

TEST(ModbusCodec, AsciiWithoutItsEndIsBadAtTheLongestFrame) {
  Buffer endless = bytes_of(":");
  endless.resize(513, '0');
  const auto d = decode_request(Framing::ascii, endless);
  EXPECT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, make_error_code(FrameError::bad_length));
  EXPECT_EQ(decode_request(Framing::ascii, ByteView(endless).first(512)).status,
            DecodeStatus::incomplete);
}

TEST(ModbusCodec, EncodeRefusesAnEmptyOrOversizedPdu) {
  EXPECT_TRUE(encode(Framing::rtu, 1, Buffer{}).empty());
  EXPECT_TRUE(encode(Framing::rtu, 1, Buffer(kMaxPdu + 1, 0x03)).empty());
  EXPECT_EQ(encode(Framing::rtu, 1, Buffer(kMaxPdu, 0x03)).size(), 256u);
  EXPECT_EQ(encode(Framing::ascii, 1, Buffer(kMaxPdu, 0x03)).size(), 513u);
}

// The Application Protocol's own request examples (6.11, 6.12, 6.14, 6.15, 6.17, 6.18, 6.21): the
// length each function and count gives is the example's length, and the counts in each agree.
TEST(ModbusCodec, RequestLengthsAreTheExamplesLengthsAndTheirCountsAgree) {
  const std::vector<Buffer> examples = {
      {0x0F, 0x00, 0x13, 0x00, 0x0A, 0x02, 0xCD, 0x01},              // 6.11
      {0x10, 0x00, 0x01, 0x00, 0x02, 0x04, 0x00, 0x0A, 0x01, 0x02},  // 6.12
      {0x14, 0x0E, 0x06, 0x00, 0x04, 0x00, 0x01, 0x00, 0x02,         // 6.14
       0x06, 0x00, 0x03, 0x00, 0x09, 0x00, 0x02},
      {0x15, 0x0D, 0x06, 0x00, 0x04, 0x00, 0x07, 0x00, 0x03,  // 6.15
       0x06, 0xAF, 0x04, 0xBE, 0x10, 0x0D},
      {0x17, 0x00, 0x03, 0x00, 0x06, 0x00, 0x0E, 0x00, 0x03, 0x06,  // 6.17
       0x00, 0xFF, 0x00, 0xFF, 0x00, 0xFF},
      {0x18, 0x04, 0xDE},                          // 6.18
      {0x2B, 0x0E, 0x01, 0x00},                    // 6.21
      {0x03, 0x00, 0x6B, 0x00, 0x03},              // 6.3
      {0x07},                                      // 6.7
      {0x16, 0x00, 0x04, 0x00, 0xF2, 0x00, 0x25},  // 6.16
  };
  for (const Buffer& pdu : examples) {
    const RequestLength l = request_length(pdu);
    EXPECT_EQ(l.status, RequestLength::Status::known) << std::hex << int{pdu[0]};
    EXPECT_EQ(l.size, pdu.size()) << std::hex << int{pdu[0]};
    EXPECT_TRUE(request_counts_agree(pdu)) << std::hex << int{pdu[0]};
    // Cut before its byte count: not known yet.
    const bool counted =
        pdu[0] == 0x0F || pdu[0] == 0x10 || pdu[0] == 0x14 || pdu[0] == 0x15 || pdu[0] == 0x17;
    if (counted) {
      EXPECT_EQ(request_length(ByteView(pdu).first(1)).status, RequestLength::Status::incomplete);
    }
  }
}

TEST(ModbusCodec, FunctionsOfAnyLengthAreUnknownAndCountsThatDisagreeAreSaid) {
  // 0x08's data is any number of words (6.8); 0x2B / 0x0D (CANopen) has no fixed request; 0x41
  // is a user-defined function (Application Protocol 5).
  for (const Buffer& pdu :
       {Buffer{0x08, 0x00, 0x00, 0x12, 0x34}, Buffer{0x2B, 0x0D, 0x00}, Buffer{0x41, 0x12, 0x34}}) {
    EXPECT_EQ(request_length(pdu).status, RequestLength::Status::unknown) << int{pdu[0]};
  }
  // A byte count that is not its quantity's: a slave reading either would end elsewhere.
  EXPECT_FALSE(request_counts_agree(Buffer{0x10, 0x00, 0x01, 0x00, 0x01, 0x04, 0, 1, 0, 2}));
  EXPECT_FALSE(request_counts_agree(Buffer{0x0F, 0x00, 0x13, 0x00, 0x0A, 0x01, 0xCD}));
  EXPECT_FALSE(request_counts_agree(
      Buffer{0x17, 0x00, 0x03, 0x00, 0x06, 0x00, 0x0E, 0x00, 0x01, 0x04, 0x00, 0xFF, 0x00, 0xFF}));
  // A file sub-request of another reference type, or cut short; record data longer than its
  // record length says.
  EXPECT_FALSE(request_counts_agree(Buffer{0x14, 0x07, 0x05, 0x00, 0x04, 0x00, 0x01, 0x00, 0x02}));
  EXPECT_FALSE(request_counts_agree(Buffer{0x14, 0x05, 0x06, 0x00, 0x04, 0x00, 0x01}));
  EXPECT_FALSE(request_counts_agree(Buffer{0x15, 0x0F, 0x06, 0x00, 0x04, 0x00, 0x07, 0x00, 0x03,
                                           0x06, 0xAF, 0x04, 0xBE, 0x10, 0x0D, 0x00, 0x00}));
  EXPECT_FALSE(request_counts_agree(Buffer{0x10, 0x00, 0x01, 0x00, 0x00, 0x00}));  // quantity 0
}

}  // namespace
}  // namespace drivegate::modbus_device
