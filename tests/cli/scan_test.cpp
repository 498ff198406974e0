// `drivegate scan`'s probing, pure (adapters/modbus/scan.h, device_id.h): which addresses, the
// frames sent, how long each waits, and how what comes back is judged.
//
// Golden frames are not computed here: they are what python3-pymodbus 3.0.0rc1 (an
// implementation nobody here wrote) builds for the same message with its ModbusRtuFramer and
// ModbusAsciiFramer: ReadHoldingRegistersRequest(0, 1), ReadDeviceInformationRequest(1, 0),
// ReadHoldingRegistersResponse([6]), ExceptionResponse(...). The identification reply is the
// example of the Toshiba TOSVERT VF-S15 communication manual (E6582051, "Read Device ID":
// "TOSHIBA", "PNE001Z", "0201", conformity 02), framed for address 17 by pymodbus.
#include "scan.h"

#include <gtest/gtest.h>

#include "codec.h"
#include "device_id.h"

namespace drivegate::modbus_device {
namespace {

using namespace std::chrono_literals;

// Application Protocol 6.3: slave 1, read holding registers from 0, quantity 1.
const Bytes kProbe1Rtu = {0x01, 0x03, 0x00, 0x00, 0x00, 0x01, 0x84, 0x0A};
const Bytes kProbe5Rtu = {0x05, 0x03, 0x00, 0x00, 0x00, 0x01, 0x85, 0x8E};
const Bytes kProbe6Rtu = {0x06, 0x03, 0x00, 0x00, 0x00, 0x01, 0x85, 0xBD};
const Bytes kProbe17Rtu = {0x11, 0x03, 0x00, 0x00, 0x00, 0x01, 0x86, 0x9A};
const std::string kProbe1Ascii = ":010300000001FB\r\n";  // Serial Line 2.5.2.1, LRC 6.2.1
// Slave 17's replies: holding 0 = 6; exception 02 (illegal data address, Application Protocol 7).
const Bytes kRegisters17 = {0x11, 0x03, 0x02, 0x00, 0x06, 0xF9, 0x85};
const Bytes kRegisters5 = {0x05, 0x03, 0x02, 0x00, 0x06, 0xC9, 0x86};
const Bytes kRegisters9 = {0x09, 0x03, 0x02, 0x00, 0x06, 0xD9, 0x87};
const Bytes kException17 = {0x11, 0x83, 0x02, 0xC1, 0x34};
// Application Protocol 6.21: read device identification, basic (01), from object 0 / object 1.
const Bytes kIdentify17 = {0x11, 0x2B, 0x0E, 0x01, 0x00, 0xB1, 0xB4};
const Bytes kIdentify17From1 = {0x11, 0x2B, 0x0E, 0x01, 0x01, 0x70, 0x74};
const Bytes kIdentityRefused17 = {0x11, 0xAB, 0x01, 0x9F, 0x35};  // 01: illegal function
const Bytes kToshiba17 = {0x11, 0x2B, 0x0E, 0x01, 0x02, 0x00, 0x00, 0x03, 0x00, 0x07, 'T', 'O',
                          'S',  'H',  'I',  'B',  'A',  0x01, 0x07, 'P',  'N',  'E',  '0', '0',
                          '1',  'Z',  0x02, 0x04, '0',  '2',  '0',  '1',  0x5B, 0x95};

Bytes bytes_of(std::string_view s) {
  return Bytes(s.begin(), s.end());
}

ScanSettings settings(std::vector<std::uint8_t> addresses, Framing framing = Framing::rtu) {
  ScanSettings s;
  s.framing = framing;
  s.char_time = character_time(19200, Parity::even, 8, 1);
  s.timeout = 100ms;
  s.addresses = std::move(addresses);
  return s;
}

TEST(ScanAddresses, RangesAndSinglesAscendingEachOnce) {
  std::string error;
  const auto all = parse_addresses("1-247", error);
  ASSERT_TRUE(all) << error;
  ASSERT_EQ(all->size(), 247u);
  EXPECT_EQ(all->front(), 1);
  EXPECT_EQ(all->back(), 247);
  EXPECT_EQ(parse_addresses("17", error), (std::vector<std::uint8_t>{17}));
  EXPECT_EQ(parse_addresses("20-22,17,21,3", error),
            (std::vector<std::uint8_t>{3, 17, 20, 21, 22}));
}

TEST(ScanAddresses, TheBroadcastAndReservedAddressesAndMalformedListsAreRefused) {
  // Serial Line 2.2: 0 is the broadcast (no slave answers it), 248..255 are reserved.
  for (const char* bad :
       {"0", "248", "0-5", "5-3", "", "1,,2", "a", "1-", "-3", "1-2-3", " 1", "17,"}) {
    std::string error;
    EXPECT_FALSE(parse_addresses(bad, error)) << bad;
    EXPECT_NE(error.find("is not an address"), std::string::npos) << bad << ": " << error;
  }
  std::string error;
  parse_addresses("1-10,300", error);
  EXPECT_EQ(error.rfind("'300'", 0), 0u) << "names the part that is wrong: " << error;
}

TEST(ScanRequests, TheProbeReadsHoldingRegisterZeroInEitherFraming) {
  Scanner rtu(settings({1}));
  const auto r = rtu.next();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->address, 1);
  EXPECT_EQ(r->frame, kProbe1Rtu);
  Scanner ascii(settings({1}, Framing::ascii));
  EXPECT_EQ(ascii.next()->frame, bytes_of(kProbe1Ascii));
}

TEST(ScanRequests, RtuKeepsThreeAndAHalfCharactersOfSilenceOrOnePointSevenFiveMs) {
  // Serial Line 2.5.1.1, rounded up to the next microsecond (line_timing.h): 9600 8N1, 3.5 x
  // 1.042 ms = 3.6458 ms; 19200 8E1, 3.5 x 0.573 ms = 2.0052 ms; above 19200 baud, the fixed
  // 1.75 ms (3.5 characters at 115200 would be 0.30 ms). ASCII frames start with ':': none.
  const auto gap = [](std::uint32_t baud, Parity parity, Framing framing) {
    ScanSettings s = settings({1}, framing);
    s.char_time = character_time(baud, parity, 8, 1);
    return Scanner(s).next()->gap;
  };
  EXPECT_EQ(gap(9600, Parity::none, Framing::rtu), 3646us);
  EXPECT_EQ(gap(19200, Parity::even, Framing::rtu), 2006us);
  EXPECT_EQ(gap(115200, Parity::none, Framing::rtu), 1750us);
  EXPECT_EQ(gap(115200, Parity::none, Framing::ascii), 0ms);
}

TEST(ScanRequests, TheWaitCountsTheRequestAndTheReplyOnTheWire) {
  // 19200 8E1: 11 bits a character, 0.573 ms. The probe's 8 bytes, 100 ms for the slave, its
  // longest reply's 7 bytes: 108.59 ms, the wire counted exactly.
  const auto c = character_time(19200, Parity::even, 8, 1);
  const auto wait = 100ms + 15 * c;
  const auto probe = 2006us + wait;  // and the gap
  Scanner scan(settings({1, 2, 3}));
  EXPECT_EQ(scan.next()->wait, wait);
  EXPECT_EQ(scan.probe_time(), probe);
  EXPECT_EQ(scan.time_left(), 3 * probe + wait);  // and the last wait for a late reply
  // At 1200 baud the wire dominates: 8 + 7 characters of 9.17 ms.
  ScanSettings slow = settings({1});
  slow.char_time = character_time(1200, Parity::even, 8, 1);
  EXPECT_EQ(Scanner(slow).next()->wait, 100ms + 15 * slow.char_time);
  // The whole default range, as `drivegate scan` says up front: 247 x 110.6 ms = 27.3 s, and one
  // wait more listening for a late reply to the last probe: 27.4 s.
  std::string error;
  EXPECT_EQ(Scanner(settings(*parse_addresses("1-247", error))).time_left(), 247 * probe + wait);
}

TEST(ScanJudging, AnyGoodReplyFromTheAddressIsASlaveRegistersOrException) {
  for (const Bytes& reply : {kRegisters17, kException17}) {
    Scanner scan(settings({17}));
    ASSERT_EQ(scan.next()->frame, kProbe17Rtu);
    EXPECT_TRUE(scan.on_receive(reply));
    ASSERT_EQ(scan.found().size(), 1u);
    EXPECT_EQ(scan.found()[0].address, 17);
    EXPECT_EQ(scan.found()[0].probe_reply, Bytes(reply.begin() + 1, reply.end() - 2));
    EXPECT_FALSE(scan.found()[0].late);
    EXPECT_EQ(scan.probed(), 1u);
    // Then its identification, at once.
    const auto id = scan.next();
    ASSERT_TRUE(id);
    EXPECT_EQ(id->frame, kIdentify17);
  }
}

TEST(ScanJudging, AReplyFedByteByByteEndsTheRequestAtItsLastByteOnly) {
  Scanner scan(settings({17}));
  scan.next();
  for (std::size_t i = 0; i + 1 < kRegisters17.size(); ++i) {
    EXPECT_FALSE(scan.on_receive(ByteView(&kRegisters17[i], 1))) << "byte " << i;
  }
  EXPECT_TRUE(scan.on_receive(ByteView(&kRegisters17.back(), 1)));
  EXPECT_EQ(scan.found().size(), 1u);
}

TEST(ScanJudging, AnAsciiReplyIsJudgedTheSameWay) {
  Scanner scan(settings({1}, Framing::ascii));
  scan.next();
  EXPECT_TRUE(scan.on_receive(bytes_of(":0103021234B4\r\n")));
  ASSERT_EQ(scan.found().size(), 1u);
  EXPECT_EQ(scan.found()[0].probe_reply, (Bytes{0x03, 0x02, 0x12, 0x34}));
}

TEST(ScanJudging, ASilentAddressIsAskedOnceAndTheNextFollows) {
  Scanner scan(settings({5, 6}));
  EXPECT_EQ(scan.next()->frame, kProbe5Rtu);
  scan.on_timeout();
  EXPECT_EQ(scan.next()->frame, kProbe6Rtu);
  scan.on_timeout();
  // The last probe went unanswered: the line is listened to for one wait more, nothing sent.
  const auto listen = scan.next();
  ASSERT_TRUE(listen);
  EXPECT_TRUE(listen->frame.empty());
  EXPECT_EQ(listen->wait, 100ms + 15 * character_time(19200, Parity::even, 8, 1));
  scan.on_timeout();
  EXPECT_FALSE(scan.next());
  EXPECT_TRUE(scan.found().empty());
  EXPECT_TRUE(scan.garbled().empty());
  EXPECT_EQ(scan.probed(), 2u);
  EXPECT_EQ(scan.time_left(), 0ms);
}

TEST(ScanJudging, DamagedBytesEarnOneRepeatThenTheAddressIsGarbled) {
  Bytes damaged = kRegisters17;
  damaged.back() ^= 0x01;  // the CRC no longer holds
  Scanner scan(settings({17, 18}));
  scan.next();
  EXPECT_FALSE(scan.on_receive(damaged));
  scan.on_timeout();
  EXPECT_EQ(scan.next()->frame, kProbe17Rtu) << "the same probe, once more";
  EXPECT_FALSE(scan.on_receive(damaged));
  scan.on_timeout();
  EXPECT_EQ(scan.next()->address, 18) << "and no third time";
  EXPECT_EQ(scan.garbled(), (std::vector<std::uint8_t>{17}));
  EXPECT_TRUE(scan.found().empty());
}

TEST(ScanJudging, AGoodReplyToTheRepeatIsASlave) {
  Bytes damaged = kRegisters17;
  damaged[3] ^= 0x40;
  Scanner scan(settings({17}));
  scan.next();
  scan.on_receive(damaged);
  scan.on_timeout();
  scan.next();
  EXPECT_TRUE(scan.on_receive(kRegisters17));
  EXPECT_EQ(scan.found().size(), 1u);
  EXPECT_TRUE(scan.garbled().empty());
}

TEST(ScanJudging, AFrameFromAnAddressNotAskedIsForeign) {
  Scanner scan(settings({17}));
  scan.next();
  EXPECT_FALSE(scan.on_receive(kRegisters9));
  EXPECT_EQ(scan.foreign_frames(), 1u);
  EXPECT_TRUE(scan.found().empty());
  EXPECT_TRUE(scan.on_receive(kRegisters17)) << "still waiting for 17";
}

TEST(ScanJudging, AReplyAfterItsWaitIsASlaveMarkedLate) {
  Scanner scan(settings({5, 6}));
  scan.next();
  scan.on_timeout();
  scan.next();
  // Slave 5's reply comes while 6 is asked: 5 is there (late); 6's wait goes on.
  EXPECT_FALSE(scan.on_receive(kRegisters5));
  ASSERT_EQ(scan.found().size(), 1u);
  EXPECT_EQ(scan.found()[0].address, 5);
  EXPECT_TRUE(scan.found()[0].late);
  EXPECT_EQ(scan.foreign_frames(), 0u);
  scan.on_timeout();
  const auto id = scan.next();
  ASSERT_TRUE(id);
  EXPECT_EQ(id->address, 5);
  EXPECT_EQ(id->frame[1], fc::encapsulated_interface);
}

// A slave that answers after its wait at the end of the range (or the only address asked) has
// no later probe to be heard during: the wait after the last probe hears it, as late.
TEST(ScanJudging, AReplyAfterTheLastProbesWaitIsHeardInTheWaitAfterIt) {
  Scanner scan(settings({5}));
  EXPECT_EQ(scan.next()->frame, kProbe5Rtu);
  scan.on_timeout();
  const auto listen = scan.next();
  ASSERT_TRUE(listen);
  EXPECT_TRUE(listen->frame.empty());
  EXPECT_FALSE(scan.on_receive(kRegisters5));
  ASSERT_EQ(scan.found().size(), 1u);
  EXPECT_EQ(scan.found()[0].address, 5);
  EXPECT_TRUE(scan.found()[0].late);
  scan.on_timeout();
  // Then it is asked who it is, as any slave found.
  const auto id = scan.next();
  ASSERT_TRUE(id);
  EXPECT_EQ(id->address, 5);
  EXPECT_EQ(id->frame[1], fc::encapsulated_interface);
  // A last probe that was answered needs no such wait.
  Scanner answered(settings({17}));
  answered.next();
  EXPECT_TRUE(answered.on_receive(kRegisters17));
  answered.next();
  EXPECT_TRUE(answered.on_receive(kIdentityRefused17));
  EXPECT_FALSE(answered.next());
  EXPECT_EQ(answered.time_left(), 0ms);
}

// A reply whose byte count says more than it carries never makes a frame: the bytes are still
// waiting for the rest when the wait runs out. That is a damaged reply (asked once more), then
// an address where bytes made no frame, as with CRC errors, never silence.
TEST(ScanJudging, AReplyShortOfItsByteCountIsDamagedNotSilence) {
  // Slave 17 answers the probe with byte count 4 and two data bytes: 11 03 04 00 06 + CRC.
  Bytes short_of_count = encode(Framing::rtu, 17, Bytes{0x03, 0x04, 0x00, 0x06});
  Scanner scan(settings({17, 18}));
  scan.next();
  EXPECT_FALSE(scan.on_receive(short_of_count));
  scan.on_timeout();
  EXPECT_EQ(scan.next()->frame, kProbe17Rtu) << "asked once more, as a damaged reply";
  EXPECT_FALSE(scan.on_receive(short_of_count));
  scan.on_timeout();
  EXPECT_EQ(scan.next()->address, 18);
  EXPECT_EQ(scan.garbled(), (std::vector<std::uint8_t>{17}));
  EXPECT_TRUE(scan.found().empty());
}

TEST(ScanJudging, ALineThatGivesBackTheRequestIsHeardThroughIt) {
  Scanner scan(settings({17}));
  scan.next();
  Bytes both = kProbe17Rtu;
  both.insert(both.end(), kRegisters17.begin(), kRegisters17.end());
  EXPECT_FALSE(scan.on_receive(ByteView(both).first(5)));
  EXPECT_TRUE(scan.on_receive(ByteView(both).subspan(5)));
  EXPECT_EQ(scan.found().size(), 1u);
  EXPECT_EQ(scan.echoes(), 1u);
  EXPECT_TRUE(scan.garbled().empty());
  // In ASCII the echo is a well-formed frame: it is still not a reply.
  Scanner ascii(settings({1}, Framing::ascii));
  ascii.next();
  EXPECT_FALSE(ascii.on_receive(bytes_of(kProbe1Ascii)));
  EXPECT_TRUE(ascii.found().empty());
  EXPECT_EQ(ascii.echoes(), 1u);
}

// Slave 17 found; its identification request is in flight.
Scanner identifying_17() {
  Scanner scan(settings({17}));
  scan.next();
  scan.on_receive(kRegisters17);
  EXPECT_EQ(scan.next()->frame, kIdentify17);
  return scan;
}

TEST(ScanIdentity, TheBasicObjectsAreKeptAsTheSlaveSentThem) {
  Scanner scan = identifying_17();
  EXPECT_TRUE(scan.on_receive(kToshiba17));
  const FoundSlave& s = scan.found()[0];
  EXPECT_EQ(s.identity_status, Identity::given);
  EXPECT_EQ(s.object(device_id_object::vendor_name), "TOSHIBA");
  EXPECT_EQ(s.object(device_id_object::product_code), "PNE001Z");
  EXPECT_EQ(s.object(device_id_object::major_minor_revision), "0201");
  EXPECT_FALSE(scan.next());
}

TEST(ScanIdentity, AnExceptionSaysItIsNotSupported) {
  Scanner scan = identifying_17();
  EXPECT_TRUE(scan.on_receive(kIdentityRefused17));
  EXPECT_EQ(scan.found()[0].identity_status, Identity::refused);
  EXPECT_EQ(scan.found()[0].identity_exception, 0x01);
}

TEST(ScanIdentity, SilenceEarnsOneRepeatThenNoReply) {
  Scanner scan = identifying_17();
  scan.on_timeout();
  EXPECT_EQ(scan.next()->frame, kIdentify17);
  scan.on_timeout();
  EXPECT_FALSE(scan.next());
  EXPECT_EQ(scan.found()[0].identity_status, Identity::no_reply);
}

TEST(ScanIdentity, MoreFollowsIsAskedForFromTheObjectTheSlaveNames) {
  Scanner scan = identifying_17();
  // 6.21: More Follows 0xFF, Next Object Id 01, one object.
  const Bytes first = {0x2B, 0x0E, 0x01, 0x01, 0xFF, 0x01, 0x01, 0x00, 0x03, 'A', 'C', 'M'};
  EXPECT_TRUE(scan.on_receive(encode(Framing::rtu, 17, first)));
  EXPECT_EQ(scan.found()[0].identity_status, Identity::pending);
  EXPECT_EQ(scan.next()->frame, kIdentify17From1);
  const Bytes rest = {0x2B, 0x0E, 0x01, 0x01, 0x00, 0x00, 0x02, 0x01,
                      0x02, 'X',  '1',  0x02, 0x03, '1',  '.',  '0'};
  EXPECT_TRUE(scan.on_receive(encode(Framing::rtu, 17, rest)));
  const FoundSlave& s = scan.found()[0];
  EXPECT_EQ(s.identity_status, Identity::given);
  EXPECT_EQ(s.identity.size(), 3u);
  EXPECT_EQ(s.object(device_id_object::product_code), "X1");
  EXPECT_FALSE(scan.next());
}

TEST(ScanIdentity, ASlaveThatNeverMovesOnIsNotAskedForever) {
  Scanner scan = identifying_17();
  // More follows, but from object 0 again: what came is kept, nothing more is asked.
  const Bytes loop = {0x2B, 0x0E, 0x01, 0x01, 0xFF, 0x00, 0x01, 0x00, 0x01, 'A'};
  EXPECT_TRUE(scan.on_receive(encode(Framing::rtu, 17, loop)));
  EXPECT_FALSE(scan.next());
  EXPECT_EQ(scan.found()[0].identity_status, Identity::given);
}

TEST(ScanIdentity, AFrameThatIsNoIdentificationIsABadReply) {
  Scanner scan = identifying_17();
  // "More Follows" 0x01: neither of the two values 6.21 allows.
  const Bytes odd = {0x2B, 0x0E, 0x01, 0x01, 0x01, 0x00, 0x01, 0x00, 0x01, 'A'};
  EXPECT_TRUE(scan.on_receive(encode(Framing::rtu, 17, odd)));
  EXPECT_EQ(scan.found()[0].identity_status, Identity::bad_reply);
}

TEST(ScanIdentity, EveryAddressThatAnswersCostsAtMostItsBoundMore) {
  // One repeated probe, and three identification requests (the basic category's three objects,
  // one a reply at least) sent twice each: the probe's 110.6 ms + 6 x (the 2.006 ms gap, the
  // request's 7 bytes, 100 ms and the longest reply's 256 bytes on the wire).
  const auto c = character_time(19200, Parity::even, 8, 1);
  EXPECT_EQ(Scanner(settings({1})).answer_time(),
            2006us + 100ms + 15 * c + 6 * (2006us + 100ms + (7 + 256) * c));
}

TEST(DeviceId, TheRequestAndTheManualsExampleReply) {
  EXPECT_EQ(device_id_request(DeviceIdCode::basic, 0), (Bytes{0x2B, 0x0E, 0x01, 0x00}));
  const ByteView pdu = ByteView(kToshiba17).subspan(1, kToshiba17.size() - 3);
  const auto r = parse_device_id_reply(pdu);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->code, 0x01);
  EXPECT_EQ(r->conformity, 0x02);
  EXPECT_FALSE(r->more_follows);
  EXPECT_EQ(r->objects,
            (std::vector<DeviceIdObject>{{0x00, "TOSHIBA"}, {0x01, "PNE001Z"}, {0x02, "0201"}}));
  EXPECT_EQ(device_id_object_name(0x02), "MajorMinorRevision");
  EXPECT_EQ(device_id_object_name(0x80), "");
}

TEST(DeviceId, MalformedRepliesAreRefused) {
  const Bytes good = {0x2B, 0x0E, 0x01, 0x01, 0x00, 0x00, 0x01, 0x00, 0x02, 'A', 'B'};
  EXPECT_TRUE(parse_device_id_reply(good));
  const Bytes short_object(good.begin(), good.end() - 1);
  Bytes trailing = good;
  trailing.push_back(0);
  Bytes more = good;
  more[4] = 0x01;  // neither 0x00 nor 0xFF
  Bytes mei = good;
  mei[1] = 0x0D;  // CANopen general reference, not read device identification
  Bytes count = good;
  count[6] = 2;
  for (const Bytes& bad : {short_object, trailing, more, mei, count, Bytes{0x2B, 0x0E, 0x01}}) {
    EXPECT_FALSE(parse_device_id_reply(bad));
  }
}

TEST(ScanProfiles, IdentificationMatchesWholeIgnoringCaseAndPadding) {
  const ProfileIdentification tosvert{"Toshiba", "PNE001Z"};
  EXPECT_TRUE(identifies(tosvert, "TOSHIBA", "PNE001Z"));
  EXPECT_TRUE(identifies(tosvert, "toshiba  ", std::string_view("PNE001Z\0\0", 9)));
  EXPECT_FALSE(identifies(tosvert, "TOSHIBA", "PNE001"));
  EXPECT_FALSE(identifies(tosvert, "TOSHIBA", "PNE001Z2"));
  EXPECT_FALSE(identifies(tosvert, "Toshiba Corp", "PNE001Z"));
  const ProfileIdentification family{"Schneider Electric", "ATV320*"};
  EXPECT_TRUE(identifies(family, "Schneider Electric", "ATV320U15N4B"));
  EXPECT_TRUE(identifies(family, "Schneider Electric", "ATV320"));
  EXPECT_FALSE(identifies(family, "Schneider Electric", "ATV32"));
  EXPECT_FALSE(identifies(family, "Schneider Electric", "ATV340U15N4"));
}

}  // namespace
}  // namespace drivegate::modbus_device
