#include "codec.h"

#include "drivegate/crc.h"

namespace drivegate::ed3100 {
namespace {

// Every frame ends in a 2-byte CRC (document, "CRC CHK Low / CRC CHK High").
constexpr std::size_t kCrcSize = 2;
// 03 / 06 requests: addr fn reg(2) count-or-value(2) CRC(2) (document, "Ask frame").
constexpr std::size_t kFixedRequestSize = 8;
// 10 request header before the data: addr fn reg(2) count(2) byteCount (document, "10H").
constexpr std::size_t kWriteMultipleHeader = 7;
// Exception reply: addr fn|80 code CRC(2) (Modbus application protocol 7).
constexpr std::size_t kExceptionSize = 5;
// 06 echo and 10 reply: addr fn reg(2) value-or-count(2) CRC(2) (document, "Response frame").
constexpr std::size_t kWriteReplySize = 8;

std::vector<std::uint16_t> words_at(ByteView rx, std::size_t offset, std::size_t count) {
  std::vector<std::uint16_t> out;
  out.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    out.push_back(be16(rx[offset + 2 * i], rx[offset + 2 * i + 1]));
  }
  return out;
}

// addr fn reg(2) word(2) CRC(2): a 03 or 06 request, a 06 echo, a 10 reply (document, "Ask
// frame", "Response frame").
Bytes fixed_frame(std::uint8_t address, std::uint8_t function, std::uint16_t reg,
                  std::uint16_t word) {
  Bytes out{address, function};
  put_be16(out, reg);
  put_be16(out, word);
  append_crc16_modbus(out);
  return out;
}

// A reply of a length known from its first bytes: nothing until all `size` bytes are in, bad when
// their CRC fails, else the reply of `function` and `kind` from `rx[0]`'s address, with what
// `fill` reads of the rest.
template <class Fill>
Decoded<Reply> checked_reply(ByteView rx, std::size_t size, std::uint8_t function, ReplyKind kind,
                             Fill fill) {
  if (rx.size() < size) return {};
  if (!crc16_modbus_holds(rx.first(size))) {
    return decoded_bad<Reply>(size, FrameError::bad_checksum);
  }
  Reply r;
  r.address = rx[0];
  r.function = function;
  r.kind = kind;
  fill(r);
  return decoded_frame(size, std::move(r));
}

}  // namespace

Bytes encode_read(std::uint8_t address, std::uint16_t reg, std::uint16_t count) {
  return fixed_frame(address, kFnRead, reg, count);
}

Bytes encode_write_single(std::uint8_t address, std::uint16_t reg, std::uint16_t value) {
  return fixed_frame(address, kFnWriteSingle, reg, value);
}

Bytes encode_write_multiple(std::uint8_t address, std::uint16_t reg,
                            std::span<const std::uint16_t> values) {
  if (values.empty() || values.size() > kMaxWriteWords) return {};
  Bytes out{address, kFnWriteMultiple};
  put_be16(out, reg);
  put_be16(out, static_cast<std::uint16_t>(values.size()));
  out.push_back(static_cast<std::uint8_t>(2 * values.size()));
  for (const std::uint16_t v : values) put_be16(out, v);
  append_crc16_modbus(out);
  return out;
}

Bytes encode_read_reply(std::uint8_t address, std::uint16_t reg,
                        std::span<const std::uint16_t> words, ReadForm form) {
  Bytes out{address, kFnRead};
  if (form == ReadForm::document) {
    put_be16(out, reg);
  } else {
    out.push_back(static_cast<std::uint8_t>(2 * words.size()));
  }
  for (const std::uint16_t w : words) put_be16(out, w);
  append_crc16_modbus(out);
  return out;
}

Bytes encode_write_multiple_reply(std::uint8_t address, std::uint16_t reg, std::uint16_t count) {
  // "respond frame only return the first six bytes of the asking frame" (document, "10H").
  return fixed_frame(address, kFnWriteMultiple, reg, count);
}

Bytes encode_exception(std::uint8_t address, std::uint8_t function, std::uint8_t code) {
  Bytes out{address, static_cast<std::uint8_t>(function | kExceptionBit), code};
  append_crc16_modbus(out);
  return out;
}

Decoded<Request> decode_request(ByteView rx) {
  if (rx.size() < 2) return {};
  std::size_t size = kFixedRequestSize;
  switch (rx[1]) {
    case kFnRead:
    case kFnWriteSingle:
      break;
    case kFnWriteMultiple:
      if (rx.size() < kWriteMultipleHeader) return {};
      if (rx[6] == 0 || rx[6] % 2 != 0) return decoded_bad<Request>(1, FrameError::bad_length);
      size = kWriteMultipleHeader + rx[6] + kCrcSize;
      break;
    default:
      return decoded_bad<Request>(1, FrameError::bad_header);
  }
  if (rx.size() < size) return {};
  const auto frame = rx.first(size);
  if (!crc16_modbus_holds(frame)) return decoded_bad<Request>(size, FrameError::bad_checksum);
  Request r;
  r.address = rx[0];
  r.function = rx[1];
  r.reg = be16(rx[2], rx[3]);
  if (r.function == kFnWriteSingle) {
    r.count = 1;
    r.words = {be16(rx[4], rx[5])};
  } else {
    r.count = be16(rx[4], rx[5]);
    if (r.function == kFnWriteMultiple) {
      if (static_cast<std::size_t>(r.count) * 2 != rx[6]) {
        return decoded_bad<Request>(size, FrameError::bad_length);
      }
      r.words = words_at(rx, kWriteMultipleHeader, r.count);
    }
  }
  return decoded_frame(size, std::move(r));
}

Decoded<Reply> decode_reply(ByteView rx, const ReplyShape& shape) {
  if (rx.size() < 2) return {};
  if (rx[1] == (shape.function | kExceptionBit)) {
    return checked_reply(rx, kExceptionSize, shape.function, ReplyKind::exception,
                         [&](Reply& r) { r.exception = rx[2]; });
  }
  if (rx[1] != shape.function) return decoded_bad<Reply>(1, FrameError::bad_header);

  if (shape.function != kFnRead) {
    return checked_reply(rx, kWriteReplySize, shape.function, ReplyKind::write_echo, [&](Reply& r) {
      r.reg = be16(rx[2], rx[3]);
      r.value = be16(rx[4], rx[5]);
    });
  }

  // 03: the standard form is one byte shorter than the document's (a byte count instead of
  // the 2-byte register echo); shared/specs/README.md: "telling them apart by CRC".
  const std::size_t data = 2 * static_cast<std::size_t>(shape.words);
  const std::size_t standard = 3 + data + kCrcSize;
  const std::size_t document = 4 + data + kCrcSize;
  if (rx.size() < 3) return {};
  const bool standard_possible = rx[2] == data;
  if (standard_possible && rx.size() >= standard && crc16_modbus_holds(rx.first(standard))) {
    Reply r;
    r.address = rx[0];
    r.function = kFnRead;
    r.kind = ReplyKind::read_standard;
    r.words = words_at(rx, 3, shape.words);
    return decoded_frame(standard, std::move(r));
  }
  return checked_reply(rx, document, kFnRead, ReplyKind::read_document, [&](Reply& r) {
    r.reg = be16(rx[2], rx[3]);
    r.words = words_at(rx, 4, shape.words);
  });
}

}  // namespace drivegate::ed3100
