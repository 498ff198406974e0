#include "serial_codec.h"

#include <algorithm>

#include "drivegate/crc.h"

namespace drivegate::modbus_serial {
namespace {

// RTU: at most 256 bytes (Serial Line 2.5.1.1).
constexpr std::size_t kRtuMaxFrame = 256;
// ASCII: ':' + 2 x (address + PDU + LRC) + CR LF; at most 513 characters (Serial Line 2.5.2.1).
constexpr std::size_t kAsciiMaxFrame = 513;
constexpr std::uint8_t kAsciiStart = ':';
constexpr std::uint8_t kCr = '\r';
constexpr std::uint8_t kLf = '\n';

// MEI type 0x0E of function 0x2B: read device identification (Application Protocol 6.21).
constexpr std::uint8_t kReadDeviceId = 0x0E;

// The public code whose layout `function` has: itself, or the `like` of a code of `layouts`, the
// exception bit kept.
std::uint8_t laid_out(std::uint8_t function, CodeLayouts layouts) {
  const auto code = static_cast<std::uint8_t>(function & ~kExceptionBit);
  for (const CodeLayout& l : layouts) {
    if (l.code == code) return static_cast<std::uint8_t>((function & kExceptionBit) | l.like);
  }
  return function;
}

// The length of request `pdu` as if its function code were `function`.
RequestLength length_of_request(std::uint8_t function, ByteView pdu) {
  using Status = RequestLength::Status;
  // A byte count at `at`, then that many bytes after the `fixed` ones.
  const auto counted = [&](std::size_t at, std::size_t fixed) -> RequestLength {
    if (pdu.size() <= at) return {Status::incomplete, 0};
    return {Status::known, fixed + pdu[at]};
  };
  switch (function) {
    case fc::read_coils:
    case fc::read_discrete_inputs:
    case fc::read_holding_registers:
    case fc::read_input_registers:
    case fc::write_single_coil:
    case fc::write_single_register:
      return {Status::known, 5};  // function, address, quantity or value
    case fc::read_exception_status:
    case fc::get_comm_event_counter:
    case fc::get_comm_event_log:
    case fc::report_server_id:
      return {Status::known, 1};  // the function alone
    case fc::write_multiple_coils:
    case fc::write_multiple_registers:
      return counted(5, 6);  // function, address, quantity, byte count, data
    case fc::read_file_record:
    case fc::write_file_record:
      return counted(1, 2);  // function, byte count, sub-requests
    case fc::mask_write_register:
      return {Status::known, 7};  // function, address, AND mask, OR mask
    case fc::read_write_registers:
      return counted(9, 10);  // function, 4 x 2-byte fields, byte count, data
    case fc::read_fifo_queue:
      return {Status::known, 3};  // function, FIFO pointer address
    case fc::encapsulated_interface:
      if (pdu.size() < 2) return {Status::incomplete, 0};
      // Function, MEI type, read device id code, object id (6.21).
      if (pdu[1] == kReadDeviceId) return {Status::known, 4};
      return {Status::unknown, 0};
    default:
      return {Status::unknown, 0};
  }
}

// How the length of an RTU reply is found from its first bytes.
enum class Length : std::uint8_t {
  fixed,         // `size` bytes in all
  count_at_2,    // a byte count at offset 2, then that many bytes: `size` + count
  count16_at_2,  // a 2-byte count at offset 2 (0x18 reply): `size` + count
  device_id,     // 0x2B / 0x0E reply: objects follow (Application Protocol 6.21)
  by_crc,        // unknown: where the CRC first holds
};
struct Rule {
  Length how = Length::by_crc;
  std::size_t size = 0;
};

// Reply lengths, address and CRC included (Application Protocol 6.x, the "Response" tables).
Rule reply_rule(std::uint8_t function) {
  if ((function & kExceptionBit) != 0) return {Length::fixed, 5};  // 7: function | 0x80, code
  switch (function) {
    case fc::read_coils:
    case fc::read_discrete_inputs:
    case fc::read_holding_registers:
    case fc::read_input_registers:
    case fc::get_comm_event_log:
    case fc::report_server_id:
    case fc::read_file_record:
    case fc::write_file_record:
    case fc::read_write_registers:
      return {Length::count_at_2, 5};  // function, byte count, data
    case fc::write_single_coil:
    case fc::write_single_register:
    case fc::get_comm_event_counter:
    case fc::write_multiple_coils:
    case fc::write_multiple_registers:
      return {Length::fixed, 8};  // function, two 2-byte fields
    case fc::read_exception_status:
      return {Length::fixed, 5};  // function, output data
    case fc::mask_write_register:
      return {Length::fixed, 10};  // function, address, AND mask, OR mask
    case fc::read_fifo_queue:
      return {Length::count16_at_2, 6};  // function, 2-byte byte count, data
    case fc::encapsulated_interface:
      return {Length::device_id, 0};
    default:
      // 0x08 among them: its echo's length depends on the sub-function (6.8).
      return {Length::by_crc, 0};
  }
}

Decoded<Adu> rtu_frame(ByteView rx, std::size_t size) {
  const ByteView frame = rx.first(size);
  if (!crc16_modbus_holds(frame)) return decoded_bad<Adu>(size, FrameError::bad_checksum);
  Adu adu;
  adu.address = frame[0];
  adu.pdu.assign(frame.begin() + 1, frame.end() - 2);
  return decoded_frame(size, std::move(adu));
}

// The whole length of the 0x2B / 0x0E reply at the start of `rx`, or nothing while it is not all
// in (Application Protocol 6.21: function, MEI type, read device id code, conformity level, more
// follows, next object id, number of objects, then id, length, value for each object).
std::optional<std::size_t> device_id_size(ByteView rx, bool& other_mei) {
  constexpr std::size_t kObjectsAt = 8;  // address + the 7 bytes before the first object
  other_mei = false;
  if (rx.size() < 3) return std::nullopt;
  if (rx[2] != kReadDeviceId) {
    other_mei = true;
    return std::nullopt;
  }
  if (rx.size() < kObjectsAt) return std::nullopt;
  const std::size_t objects = rx[7];
  std::size_t at = kObjectsAt;
  for (std::size_t i = 0; i < objects; ++i) {
    if (rx.size() < at + 2) return std::nullopt;
    at += 2 + rx[at + 1];
    if (at + 2 > kRtuMaxFrame) return at + 2;  // too long: the caller says so
  }
  return at + 2;
}

// A frame of a function whose length the codec does not know: it ends where the bytes so far
// first carry a good CRC (crc_end). A buffer of a whole frame's length without one is a bad frame.
Decoded<Adu> decode_rtu_by_crc(ByteView rx) {
  if (const auto size = crc_end(rx)) return rtu_frame(rx, *size);
  if (rx.size() >= kRtuMaxFrame) return decoded_bad<Adu>(kRtuMaxFrame, FrameError::bad_checksum);
  return {};
}

// The whole length of the RTU reply at the start of `rx` (address and CRC included), or the
// decoding of one that is not all in yet or is delimited by its CRC (`done`).
std::optional<std::size_t> reply_size(ByteView rx, CodeLayouts layouts, Decoded<Adu>& done) {
  const Rule rule = reply_rule(laid_out(rx[1], layouts));
  switch (rule.how) {
    case Length::fixed:
      return rule.size;
    case Length::count_at_2:
      if (rx.size() <= 2) return std::nullopt;
      return rule.size + rx[2];
    case Length::count16_at_2:
      if (rx.size() < 4) return std::nullopt;
      return rule.size + be16(rx[2], rx[3]);
    case Length::device_id: {
      bool other_mei = false;
      const auto s = device_id_size(rx, other_mei);
      if (other_mei) done = decode_rtu_by_crc(rx);
      return s;
    }
    case Length::by_crc:
      done = decode_rtu_by_crc(rx);
      return std::nullopt;
  }
  return std::nullopt;
}

Decoded<Adu> decode_rtu(ByteView rx, bool reply, CodeLayouts layouts) {
  if (rx.empty()) return {};
  if (rx[0] > kMaxSlave) return decoded_bad<Adu>(1, FrameError::bad_header);
  if (rx.size() < 2) return {};
  std::size_t size = 0;
  if (reply) {
    Decoded<Adu> done;
    const auto s = reply_size(rx, layouts, done);
    if (!s) return done;
    size = *s;
  } else {
    const RequestLength length = length_of_request(laid_out(rx[1], layouts), rx.subspan(1));
    switch (length.status) {
      case RequestLength::Status::incomplete:
        return {};
      case RequestLength::Status::unknown:
        return decode_rtu_by_crc(rx);
      case RequestLength::Status::known:
        size = length.size + kRtuOverhead;
        break;
    }
  }
  if (size > kRtuMaxFrame) return decoded_bad<Adu>(1, FrameError::bad_length);
  if (rx.size() < size) return {};
  return rtu_frame(rx, size);
}

int hex_value(std::uint8_t c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

Decoded<Adu> decode_ascii(ByteView rx) {
  if (rx.empty()) return {};
  if (rx[0] != kAsciiStart) {
    // Noise up to the next ':' (a frame may start there).
    const auto next = std::find(rx.begin() + 1, rx.end(), kAsciiStart);
    return decoded_bad<Adu>(static_cast<std::size_t>(next - rx.begin()), FrameError::bad_header);
  }
  const std::size_t most = std::min(rx.size(), kAsciiMaxFrame);
  std::size_t end = 0;  // index of the LF
  for (std::size_t i = 1; i < most; ++i) {
    if (rx[i] == kAsciiStart) {
      // A new ':' before CR LF: the frame so far was cut short (Serial Line 2.5.2.1: a ':'
      // always starts a new message).
      return decoded_bad<Adu>(i, FrameError::bad_length);
    }
    if (rx[i] == kLf) {
      end = i;
      break;
    }
  }
  if (end == 0) {
    if (rx.size() >= kAsciiMaxFrame)
      return decoded_bad<Adu>(kAsciiMaxFrame, FrameError::bad_length);
    return {};
  }
  const std::size_t size = end + 1;
  if (rx[end - 1] != kCr) return decoded_bad<Adu>(size, FrameError::bad_field);
  const ByteView hex = rx.subspan(1, end - 2);
  // Address, function and LRC at least, two characters each.
  if (hex.size() % 2 != 0 || hex.size() < 6) return decoded_bad<Adu>(size, FrameError::bad_length);
  Bytes bytes;
  bytes.reserve(hex.size() / 2);
  for (std::size_t i = 0; i < hex.size(); i += 2) {
    const int hi = hex_value(hex[i]);
    const int lo = hex_value(hex[i + 1]);
    if (hi < 0 || lo < 0) return decoded_bad<Adu>(size, FrameError::bad_field);
    bytes.push_back(static_cast<std::uint8_t>(hi * 16 + lo));
  }
  const ByteView body = ByteView(bytes).first(bytes.size() - 1);
  if (lrc(body) != bytes.back()) return decoded_bad<Adu>(size, FrameError::bad_checksum);
  if (body[0] > kMaxSlave) return decoded_bad<Adu>(size, FrameError::bad_header);
  Adu adu;
  adu.address = body[0];
  adu.pdu.assign(body.begin() + 1, body.end());
  return decoded_frame(size, std::move(adu));
}

}  // namespace

std::uint8_t lrc(ByteView data) {
  // Serial Line 6.2.1: add the bytes, discarding carries, then take the two's complement.
  std::uint8_t sum = 0;
  for (const std::uint8_t b : data) sum = static_cast<std::uint8_t>(sum + b);
  return static_cast<std::uint8_t>(-sum);
}

Bytes encode(Framing framing, std::uint8_t address, ByteView pdu) {
  if (pdu.empty() || pdu.size() > kMaxPdu) return {};
  Bytes body;
  body.reserve(pdu.size() + kRtuOverhead);
  body.push_back(address);
  body.insert(body.end(), pdu.begin(), pdu.end());
  if (framing == Framing::rtu) {
    append_crc16_modbus(body);  // low byte first (Serial Line 6.2.2)
    return body;
  }
  body.push_back(lrc(body));
  static constexpr char kHex[] = "0123456789ABCDEF";
  Bytes out;
  out.reserve(2 * body.size() + 3);
  out.push_back(kAsciiStart);
  for (const std::uint8_t b : body) {
    out.push_back(static_cast<std::uint8_t>(kHex[b >> 4]));
    out.push_back(static_cast<std::uint8_t>(kHex[b & 0x0F]));
  }
  out.push_back(kCr);
  out.push_back(kLf);
  return out;
}

Decoded<Adu> decode_reply(Framing framing, ByteView rx, CodeLayouts layouts) {
  return framing == Framing::rtu ? decode_rtu(rx, true, layouts) : decode_ascii(rx);
}

Decoded<Adu> decode_request(Framing framing, ByteView rx, CodeLayouts layouts) {
  return framing == Framing::rtu ? decode_rtu(rx, false, layouts) : decode_ascii(rx);
}

// One running CRC over the bytes: each prefix's is the one before it and a byte more, so a noisy
// line costs a pass over the buffer per read, not a CRC per prefix.
std::optional<std::size_t> crc_end(ByteView rx) {
  const std::size_t most = std::min(rx.size(), kRtuMaxFrame);
  std::uint16_t crc = 0xFFFF;  // of rx[0, k)
  for (std::size_t k = 0; k + 2 <= most; ++k) {
    if (k + 2 >= kRtuMinFrame && rx[k] == lo8(crc) && rx[k + 1] == hi8(crc)) return k + 2;
    crc = crc16_modbus_update(crc, rx[k]);
  }
  return std::nullopt;
}

RequestLength request_length(ByteView pdu) {
  if (pdu.empty()) return {RequestLength::Status::incomplete, 0};
  return length_of_request(pdu[0], pdu);
}

bool request_counts_agree(ByteView pdu) {
  if (pdu.empty()) return false;
  // File records (6.14, 6.15): a sub-request is reference type 6, file number, record number
  // and record length (7 bytes); 0x15's carries that many words of record data after it.
  constexpr std::uint8_t kReferenceType = 6;
  constexpr std::size_t kSubRequest = 7;
  switch (pdu[0]) {
    case fc::write_multiple_coils:        // 6.11: N coils in ceil(N / 8) bytes
    case fc::write_multiple_registers: {  // 6.12: N registers in 2 x N bytes
      if (pdu.size() < 6) return false;
      const std::size_t n = be16(pdu[3], pdu[4]);
      const std::size_t bytes = pdu[0] == fc::write_multiple_coils ? (n + 7) / 8 : 2 * n;
      return n >= 1 && pdu[5] == bytes;
    }
    case fc::read_write_registers: {  // 6.17: N registers written in 2 x N bytes
      if (pdu.size() < 10) return false;
      const std::size_t n = be16(pdu[7], pdu[8]);
      return n >= 1 && pdu[9] == 2 * n;
    }
    case fc::read_file_record:
    case fc::write_file_record: {
      if (pdu.size() < 2 || pdu.size() != 2u + pdu[1]) return false;
      const bool data = pdu[0] == fc::write_file_record;
      std::size_t at = 2;
      while (at < pdu.size()) {
        if (pdu.size() - at < kSubRequest || pdu[at] != kReferenceType) return false;
        at += kSubRequest;
        if (data) at += 2 * std::size_t{be16(pdu[at - 2], pdu[at - 1])};
      }
      return at == pdu.size() && pdu.size() > 2;
    }
    default:
      return true;
  }
}

Bytes exception_pdu(std::uint8_t function, std::uint8_t code) {
  return {static_cast<std::uint8_t>(function | kExceptionBit), code};
}

std::optional<std::uint8_t> exception_code(ByteView pdu) {
  if (pdu.size() != 2 || (pdu[0] & kExceptionBit) == 0) return std::nullopt;
  return pdu[1];
}

}  // namespace drivegate::modbus_serial
