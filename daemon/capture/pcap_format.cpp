#include "capture/pcap_format.h"

#include <algorithm>

namespace drivegate::capture {

namespace {
void put_u16le(std::string& out, std::uint16_t v) {
  out.push_back(static_cast<char>(v & 0xFF));
  out.push_back(static_cast<char>(v >> 8));
}
void put_u32le(std::string& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}
void put_text(std::string& out, std::string_view text) {
  const std::size_t n = std::min<std::size_t>(text.size(), 255);
  out.push_back(static_cast<char>(n));
  out.append(text.substr(0, n));
}
}  // namespace

std::string pcap_global_header(std::uint32_t snaplen) {
  std::string out;
  out.reserve(kGlobalHeaderSize);
  put_u32le(out, kPcapMagic);
  put_u16le(out, 2);  // version 2.4
  put_u16le(out, 4);
  put_u32le(out, 0);  // thiszone: timestamps are UTC
  put_u32le(out, 0);  // sigfigs
  put_u32le(out, snaplen);
  put_u32le(out, kLinktypeUser0);
  return out;
}

std::string pseudo_header(const FrameRecord& r) {
  std::string out;
  out.push_back(static_cast<char>(kPseudoHeaderVersion));
  out.push_back(static_cast<char>(r.direction));
  out.push_back(static_cast<char>(r.flags));
  out.push_back(static_cast<char>(r.unit_id));
  put_text(out, r.adapter);
  put_text(out, r.device);
  return out;
}

void append_pcap_record(std::string& out, const FrameRecord& r, std::uint32_t snaplen) {
  const std::string head = pseudo_header(r);
  const std::size_t length = head.size() + r.bytes.size();
  const std::size_t kept = std::min<std::size_t>(length, snaplen);
  const std::int64_t us = std::max<std::int64_t>(r.unix_us, 0);
  put_u32le(out, static_cast<std::uint32_t>(us / 1'000'000));
  put_u32le(out, static_cast<std::uint32_t>(us % 1'000'000));
  put_u32le(out, static_cast<std::uint32_t>(kept));
  put_u32le(out, static_cast<std::uint32_t>(length));
  std::string packet = head;
  packet.append(reinterpret_cast<const char*>(r.bytes.data()), r.bytes.size());
  out.append(packet, 0, kept);
}

}  // namespace drivegate::capture
