// The pcap of a capture, byte for byte (docs/capture.md): global header, record header,
// pseudo-header; and the tap that turns engine frames into records, within its size cap.
#include "capture/pcap_format.h"

#include <gtest/gtest.h>

#include <string>
#include <unordered_map>
#include <vector>

#include "capture/pcap_tap.h"

namespace drivegate::capture {
namespace {

std::vector<std::uint8_t> bytes_of(const std::string& s) {
  return {s.begin(), s.end()};
}

TEST(PcapFormat, GlobalHeaderIsClassicLittleEndianUser0) {
  const std::vector<std::uint8_t> golden = {
      0xd4, 0xc3, 0xb2, 0xa1,  // magic a1b2c3d4, microseconds, little-endian
      0x02, 0x00, 0x04, 0x00,  // version 2.4
      0x00, 0x00, 0x00, 0x00,  // thiszone
      0x00, 0x00, 0x00, 0x00,  // sigfigs
      0xff, 0xff, 0x00, 0x00,  // snaplen 65535
      0x93, 0x00, 0x00, 0x00,  // LINKTYPE_USER0 = 147
  };
  EXPECT_EQ(bytes_of(pcap_global_header()), golden);
}

TEST(PcapFormat, RecordCarriesTimeLengthsPseudoHeaderAndFrame) {
  const std::vector<std::uint8_t> frame = {0xA5, 0x05, 0, 0, 0, 0, 0, 0, 0, 0, 0xA0};
  FrameRecord r;
  r.unix_us = 1'700'000'000'123'456;
  r.direction = 0;
  r.flags = 0x20;
  r.unit_id = 7;
  r.adapter = "nidec-washer";
  r.device = "washer";
  r.bytes = frame;
  std::string out;
  append_pcap_record(out, r);
  std::vector<std::uint8_t> golden = {
      0x00, 0xf1, 0x53, 0x65,  // 1700000000 s
      0x40, 0xe2, 0x01, 0x00,  // 123456 us
      0x23, 0x00, 0x00, 0x00,  // captured: 24 (pseudo-header) + 11 (frame) = 35
      0x23, 0x00, 0x00, 0x00,  // original length, the same
      0x01,                    // pseudo-header version
      0x00,                    // gateway -> drive
      0x20,                    // flags: resend
      0x07,                    // unit id
      12,   'n',  'i',  'd',  'e', 'c', '-', 'w', 'a', 's',
      'h',  'e',  'r',  6,    'w', 'a', 's', 'h', 'e', 'r',
  };
  golden.insert(golden.end(), frame.begin(), frame.end());
  ASSERT_EQ(golden.size(), 16u + 0x23u);
  EXPECT_EQ(bytes_of(out), golden);
}

TEST(PcapFormat, NoDeviceGivesEmptyNames) {
  const std::vector<std::uint8_t> noise = {0xFF};
  FrameRecord r;
  r.direction = 1;
  r.flags = 0x02;
  r.bytes = noise;
  EXPECT_EQ(bytes_of(pseudo_header(r)), (std::vector<std::uint8_t>{1, 1, 2, 0, 0, 0}));
}

TEST(PcapFormat, SnaplenCutsThePacketButKeepsItsLength) {
  const std::vector<std::uint8_t> frame(100, 0x55);
  FrameRecord r;
  r.bytes = frame;
  std::string out;
  append_pcap_record(out, r, 50);
  ASSERT_EQ(out.size(), 16u + 50u);
  EXPECT_EQ(static_cast<std::uint8_t>(out[8]), 50);        // captured
  EXPECT_EQ(static_cast<std::uint8_t>(out[12]), 6 + 100);  // original
}

TEST(PcapFormat, LongNamesAreCutAt255) {
  const std::string name(300, 'x');
  FrameRecord r;
  r.device = name;
  const std::string h = pseudo_header(r);
  EXPECT_EQ(h.size(), 6u + 255u);
  EXPECT_EQ(static_cast<std::uint8_t>(h[5]), 255);
}

TEST(PcapTap, StampsWallClockNamesTheStationAndStopsAtItsCap) {
  const Station* washer = reinterpret_cast<const Station*>(0x1000);  // identity only
  std::unordered_map<const Station*, StationInfo> stations{{washer, {"nidec-washer", "w", 3}}};
  const TimePoint t0{std::chrono::seconds(1000)};
  int calls = 0;
  PcapTap tap(stations, t0, 1'700'000'000'000'000, 24 + 2 * (16 + 19 + 2), [&] { ++calls; });
  const std::vector<std::uint8_t> frame = {0x01, 0x02};
  tap.on_frame({FrameDirection::from_drive, 0, washer, frame}, t0 + std::chrono::milliseconds(5));
  std::string got = tap.take();
  ASSERT_EQ(got.size(), 24u + 16u + 19u + 2u);  // pseudo-header 4 + 13 + 2
  EXPECT_EQ(got.substr(0, 24), pcap_global_header());
  EXPECT_EQ(static_cast<std::uint8_t>(got[24 + 4]), 0x88);  // 5000 us = 0x1388
  EXPECT_EQ(static_cast<std::uint8_t>(got[24 + 5]), 0x13);
  EXPECT_EQ(got.substr(40, 6), std::string("\x01\x01\x00\x03\x0cn", 6));
  EXPECT_TRUE(tap.take().empty());
  tap.on_frame({FrameDirection::to_drive, 0, washer, frame}, t0);
  EXPECT_FALSE(tap.full());
  tap.on_frame({FrameDirection::to_drive, 0, washer, frame}, t0);  // past the cap
  EXPECT_TRUE(tap.full());
  EXPECT_EQ(tap.frames(), 2u);
  EXPECT_EQ(calls, 3);
  tap.on_frame({FrameDirection::to_drive, 0, nullptr, frame}, t0);
  EXPECT_EQ(tap.take().size(), 16u + 19u + 2u);  // the second only
}

}  // namespace
}  // namespace drivegate::capture
