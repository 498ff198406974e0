// The pcap file format of a capture (docs/capture.md): the classic libpcap global header and
// records, link type LINKTYPE_USER0 (147), each packet one protocol frame behind a small
// pseudo-header naming its direction, what the engine made of it, and its device and adapter.
// Pure: bytes in, bytes out; the HTTP stream and the tests both use it.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "drivegate/bytes.h"

namespace drivegate::capture {

inline constexpr std::uint32_t kPcapMagic = 0xa1b2c3d4;  // microsecond timestamps
inline constexpr std::uint32_t kLinktypeUser0 = 147;
inline constexpr std::uint32_t kSnapLen = 65535;
inline constexpr std::uint8_t kPseudoHeaderVersion = 1;
inline constexpr std::size_t kGlobalHeaderSize = 24;
inline constexpr std::size_t kRecordHeaderSize = 16;

// One frame as a capture records it.
struct FrameRecord {
  std::int64_t unix_us = 0;    // wall-clock time, microseconds since the Unix epoch
  std::uint8_t direction = 0;  // 0 gateway -> drive, 1 drive -> gateway
  std::uint8_t flags = 0;      // bus/frame_tap.h frame_flags
  std::uint8_t unit_id = 0;    // the device's Modbus unit id; 0: none
  std::string_view adapter;    // adapter id ("nidec-washer"); empty: no device
  std::string_view device;     // device name from the configuration
  ByteView bytes;              // the frame as on the wire
};

// The 24-byte global header, little-endian (magic a1b2c3d4, version 2.4, snaplen, link type).
std::string pcap_global_header(std::uint32_t snaplen = kSnapLen);
// The pseudo-header alone: version, direction, flags, unit id, adapter id and device name, each
// a length byte and its bytes (cut at 255).
std::string pseudo_header(const FrameRecord& r);
// One record: its 16-byte header and the packet (pseudo-header + frame), appended to `out`. A
// packet longer than `snaplen` is cut to it (the record keeps the original length).
void append_pcap_record(std::string& out, const FrameRecord& r, std::uint32_t snaplen = kSnapLen);

}  // namespace drivegate::capture
