#include "codec.h"

#include <numeric>
#include <utility>

namespace drivegate::mdriver {
namespace {

bool known_command(std::uint8_t cmd) {
  return cmd == static_cast<std::uint8_t>(Cmd::check) || cmd == static_cast<std::uint8_t>(Cmd::run);
}

std::uint8_t sum(ByteView bytes) {
  return static_cast<std::uint8_t>(std::accumulate(bytes.begin(), bytes.end(), 0u));
}

// One frame at the start of rx, no resynchronisation.
Decoded<Frame> decode_at(ByteView rx) {
  // Section 3: D2 is one of the two commands; anything else cannot start a frame.
  if (rx.size() > 2 && !known_command(rx[2])) return decoded_bad<Frame>(1, FrameError::bad_header);
  if (rx.size() < kHeaderSize) return {};
  const std::size_t data_len = std::size_t{rx[3]} + 1;  // D3 = data length - 1
  if (data_len > kMaxData) return decoded_bad<Frame>(1, FrameError::bad_length);
  const std::size_t total = kOverhead + data_len;
  if (rx.size() < total) return {};
  if (sum(rx.first(total)) != kChecksumTotal)
    return decoded_bad<Frame>(total, FrameError::bad_checksum);
  Frame f{
      rx[0], rx[1], rx[2], {rx.begin() + kHeaderSize, rx.begin() + static_cast<long>(total - 1)}};
  return decoded_frame<Frame>(total, std::move(f));
}

}  // namespace

std::uint8_t checksum(ByteView bytes) {
  return static_cast<std::uint8_t>(kChecksumTotal - sum(bytes));
}

Bytes encode(const Frame& f) {
  Bytes out;
  out.reserve(kOverhead + f.data.size());
  out.push_back(f.src);
  out.push_back(f.dst);
  out.push_back(f.cmd);
  out.push_back(static_cast<std::uint8_t>(f.data.size() - 1));
  out.insert(out.end(), f.data.begin(), f.data.end());
  out.push_back(checksum(out));
  return out;
}

Decoded<Frame> decode(ByteView rx) {
  Decoded<Frame> d = decode_at(rx);
  if (d.status != DecodeStatus::bad || d.error != FrameError::bad_checksum) return d;
  // A truncated frame followed by a whole one looks like one frame-shaped run with a bad sum:
  // drop only the bytes before a checked frame that starts inside it.
  for (std::size_t k = 1; k < d.consumed; ++k) {
    if (decode_at(rx.subspan(k)).status == DecodeStatus::frame) {
      return decoded_bad<Frame>(k, FrameError::bad_header);
    }
  }
  return d;
}

Bytes encode_check(std::uint8_t master, std::uint8_t device) {
  return encode({master,
                 device,
                 static_cast<std::uint8_t>(Cmd::check),
                 {kFixedCode.begin(), kFixedCode.end()}});
}

Bytes encode_run(std::uint8_t master, std::uint8_t device, std::uint8_t code, std::uint8_t change) {
  // Section 3 No.2: D4 target code, D5 change time, D6 reserved 00.
  return encode({master, device, static_cast<std::uint8_t>(Cmd::run), {code, change, 0x00}});
}

Bytes encode_check_reply(std::uint8_t device, std::uint8_t master,
                         const std::array<std::uint8_t, 4>& code) {
  return encode(
      {device, master, static_cast<std::uint8_t>(Cmd::check), {code.begin(), code.end()}});
}

Bytes encode_run_reply(std::uint8_t device, std::uint8_t master, const RunReply& r) {
  return encode({device,
                 master,
                 static_cast<std::uint8_t>(Cmd::run),
                 {r.target_code, r.actual_code, r.reserved, r.error_code, r.ipm_temp_c, r.info[0],
                  r.info[1], r.info[2]}});
}

std::optional<std::array<std::uint8_t, 4>> parse_check(const Frame& f) {
  // Section 3 No.1: D3/R3 = 03, four code bytes.
  if (f.cmd != static_cast<std::uint8_t>(Cmd::check) || f.data.size() != 4) return std::nullopt;
  return std::array<std::uint8_t, 4>{f.data[0], f.data[1], f.data[2], f.data[3]};
}

std::optional<RunReply> parse_run_reply(const Frame& f) {
  // Section 3 No.2: R3 = 07, eight data bytes R4..R11.
  if (f.cmd != static_cast<std::uint8_t>(Cmd::run) || f.data.size() != 8) return std::nullopt;
  const auto& d = f.data;
  return RunReply{d[0], d[1], d[2], d[3], d[4], {d[5], d[6], d[7]}};
}

std::optional<RunRequest> parse_run_request(const Frame& f) {
  // Section 3 No.2: D3 = 02, three data bytes D4..D6.
  if (f.cmd != static_cast<std::uint8_t>(Cmd::run) || f.data.size() != 3) return std::nullopt;
  return RunRequest{f.data[0], f.data[1]};
}

}  // namespace drivegate::mdriver
