#include "mbap.h"

#include <array>
#include <string>
#include <string_view>

#include "drivegate/bytes.h"

namespace drivegate::modbus {
namespace {

class MbapCategory final : public std::error_category {
 public:
  const char* name() const noexcept override { return "mbap"; }
  std::string message(int code) const override {
    // By MbapError, from 1.
    static constexpr std::array<std::string_view, 4> kMessages = {
        "MBAP protocol id is not 0", "MBAP length is 0", "MBAP length is 1 (no function code)",
        "MBAP length is over 254"};
    const auto i = static_cast<std::size_t>(code) - 1;
    return std::string(code >= 1 && i < kMessages.size() ? kMessages[i] : "unknown MBAP error");
  }
};

}  // namespace

const std::error_category& mbap_category() {
  static const MbapCategory category;
  return category;
}

std::error_code make_error_code(MbapError e) {
  return {static_cast<int>(e), mbap_category()};
}

MbapParse parse_mbap(std::span<const std::uint8_t> buffer) {
  MbapParse r;
  // Implementation Guide 3.1.3: bytes 0-1 transaction id, 2-3 protocol id, 4-5 length, 6 unit id.
  if (buffer.size() >= 2) r.header.transaction = be16_at(buffer, 0);
  if (buffer.size() < 4) return r;
  r.header.protocol = be16_at(buffer, 2);
  if (r.header.protocol != 0) {
    r.status = MbapParse::Status::bad;
    r.error = MbapError::bad_protocol_id;
    return r;
  }
  if (buffer.size() < 6) return r;
  r.header.length = be16_at(buffer, 4);
  if (r.header.length == 0 || r.header.length == 1 || r.header.length > kMaxMbapLength) {
    r.status = MbapParse::Status::bad;
    r.error = r.header.length == 0   ? MbapError::length_zero
              : r.header.length == 1 ? MbapError::empty_pdu
                                     : MbapError::length_too_long;
    return r;
  }
  const std::size_t total = 6 + std::size_t{r.header.length};
  if (buffer.size() < total) {
    if (buffer.size() >= kMbapHeaderSize) r.header.unit = buffer[6];
    return r;
  }
  r.header.unit = buffer[6];
  r.status = MbapParse::Status::good;
  r.pdu = buffer.subspan(kMbapHeaderSize, total - kMbapHeaderSize);
  r.consumed = total;
  return r;
}

void put_mbap(std::span<std::uint8_t> out, std::uint16_t transaction, std::uint8_t unit,
              std::size_t pdu_size) {
  const auto length = static_cast<std::uint16_t>(pdu_size + 1);  // unit id + PDU (3.1.3)
  out[0] = static_cast<std::uint8_t>(transaction >> 8);
  out[1] = static_cast<std::uint8_t>(transaction);
  out[2] = 0;  // protocol id 0 = Modbus (3.1.3)
  out[3] = 0;
  out[4] = static_cast<std::uint8_t>(length >> 8);
  out[5] = static_cast<std::uint8_t>(length);
  out[6] = unit;
}

}  // namespace drivegate::modbus
