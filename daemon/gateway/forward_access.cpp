#include "gateway/forward_access.h"

#include <fmt/format.h>

#include <algorithm>
#include <optional>
#include <vector>

#include "drivegate/crc.h"
#include "modbus_serial/serial_codec.h"

namespace drivegate {
namespace {

namespace fc = modbus_serial::fc;
using modbus_serial::RequestLength;

using modbus_serial::kRtuMinFrame;
using modbus_serial::kRtuOverhead;

AccessLevel level_of(std::span<const std::uint8_t> pdu) {
  // Function codes of the MODBUS Application Protocol Specification V1.1b3.
  switch (pdu[0]) {
    case fc::read_coils:              // 6.1
    case fc::read_discrete_inputs:    // 6.2
    case fc::read_holding_registers:  // 6.3
    case fc::read_input_registers:    // 6.4
    case fc::read_exception_status:   // 6.7
    case fc::get_comm_event_counter:  // 6.9
    case fc::get_comm_event_log:      // 6.10
    case fc::report_server_id:        // 6.13
    case fc::read_file_record:        // 6.14
    case fc::read_fifo_queue:         // 6.18
      return AccessLevel::read;
    case fc::diagnostics:  // 6.8: only sub-function 0x0000, return query data, changes nothing
      return pdu.size() >= 3 && pdu[1] == 0x00 && pdu[2] == 0x00 ? AccessLevel::read
                                                                 : AccessLevel::maintain;
    case fc::encapsulated_interface:  // 6.19 / 6.21: MEI type 0x0E, read device identification
      return pdu.size() >= 2 && pdu[1] == 0x0E ? AccessLevel::read : AccessLevel::maintain;
    default:
      return AccessLevel::maintain;
  }
}

// The whole sizes (address, PDU, CRC) a length-parsing slave may take the request at the start
// of `rx` to have, where it can tell: by the codec's lengths, and FC 08 at its forwarded length.
// A user-defined code (Application Protocol 5) has the layout its drive's manual gives it, such
// as the "write without saving" 0x41 laid out as 0x06 (docs/profiles.md, "Writes that are not
// saved"): either public write's, whichever a slave knows it by.
std::vector<std::size_t> taken_at(ByteView rx) {
  if (rx.size() < 2 || rx[0] > modbus_serial::kMaxSlave) return {};
  if (rx[1] == fc::diagnostics) return {kForwardedDiagnostics + kRtuOverhead};
  const auto size_as = [&](std::uint8_t layout) -> std::optional<std::size_t> {
    // The PDU's first bytes with the code it is laid out as: FC 16's byte count is its sixth.
    Bytes head(rx.begin() + 1, rx.begin() + static_cast<long>(std::min<std::size_t>(rx.size(), 7)));
    head[0] = layout;
    const RequestLength l = modbus_serial::request_length(head);
    if (l.status != RequestLength::Status::known) return std::nullopt;
    return l.size + kRtuOverhead;
  };
  std::vector<std::size_t> sizes;
  if (modbus_serial::user_defined_code(rx[1])) {
    for (const std::uint8_t layout : {fc::write_single_register, fc::write_multiple_registers}) {
      if (const auto size = size_as(layout)) sizes.push_back(*size);
    }
    return sizes;
  }
  const RequestLength l = modbus_serial::request_length(rx.subspan(1));
  if (l.status == RequestLength::Status::known) sizes.push_back(l.size + kRtuOverhead);
  return sizes;
}

// Where a slave would find a request in `frame` (address, PDU, CRC) other than the frame itself:
// byte 0 when a CRC holds before the end (a slave delimiting by CRC ends the frame there), else
// the offset of a whole request that starts inside it.
std::optional<std::size_t> frame_inside(ByteView frame) {
  if (modbus_serial::crc_end(frame) != frame.size()) return 0;
  for (std::size_t at = 1; at + kRtuMinFrame <= frame.size(); ++at) {
    const ByteView rest = frame.subspan(at);
    for (const std::size_t size : taken_at(rest)) {
      if (size <= rest.size() && crc16_modbus_holds(rest.first(size))) return at;
    }
  }
  return std::nullopt;
}

// Why `pdu` is not one whole, well-formed request of a known length, if it is not.
std::optional<ForwardVerdict> malformed(std::span<const std::uint8_t> pdu) {
  const auto refused = [](Outcome o, std::string why) {
    return ForwardVerdict{AccessLevel::maintain, o, std::move(why)};
  };
  const std::uint8_t function = pdu[0];
  std::size_t size = 0;
  if (function == fc::diagnostics) {
    size = kForwardedDiagnostics;
  } else {
    const RequestLength l = modbus_serial::request_length(pdu);
    switch (l.status) {
      case RequestLength::Status::unknown:
        return refused(
            Outcome::denied,
            fmt::format("function 0x{:02X}: its length is unknown, forwarded to none", function));
      case RequestLength::Status::incomplete:
        return refused(Outcome::invalid_value,
                       fmt::format("function 0x{:02X}: {} bytes, cut short", function, pdu.size()));
      case RequestLength::Status::known:
        size = l.size;
        break;
    }
  }
  if (pdu.size() != size) {
    return refused(Outcome::invalid_value,
                   fmt::format("function 0x{:02X}: {} bytes where its length is {}", function,
                               pdu.size(), size));
  }
  if (!modbus_serial::request_counts_agree(pdu)) {
    return refused(Outcome::invalid_value,
                   fmt::format("function 0x{:02X}: its counts disagree", function));
  }
  return std::nullopt;
}

}  // namespace

ForwardVerdict judge_forward(std::span<const std::uint8_t> pdu, std::uint8_t address) {
  if (pdu.empty() || pdu.size() > modbus_serial::kMaxPdu) {
    return {AccessLevel::maintain, Outcome::invalid_value,
            fmt::format("{} bytes: no request", pdu.size())};
  }
  if (auto bad = malformed(pdu)) {
    bad->needs = level_of(pdu);
    return *bad;
  }
  ForwardVerdict v;
  v.needs = level_of(pdu);
  const Bytes frame = modbus_serial::encode(modbus_serial::Framing::rtu, address, pdu);
  if (const auto at = frame_inside(frame)) {
    v.refusal = Outcome::invalid_value;
    v.why = *at == 0 ? std::string("a CRC holds before its end: a slave would end it early")
                     : fmt::format("a whole request inside it, at byte {} of its frame", *at);
  }
  return v;
}

}  // namespace drivegate
