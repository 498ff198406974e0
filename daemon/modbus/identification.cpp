// Function 0x2B / MEI type 0x0E, Read Device Identification (Application Protocol V1.1b3, 6.21).
// Only the basic category exists (VendorName, ProductCode, MajorMinorRevision), with stream and
// individual access: conformity level 0x81.
#include <algorithm>

#include "pdu.h"

namespace drivegate::modbus {
namespace {

constexpr std::uint8_t kMeiDeviceIdentification = 0x0E;  // 6.21: MEI type
// 6.21 Read Device ID codes: 01 basic, 02 regular, 03 extended (stream access), 04 individual.
constexpr std::uint8_t kReadBasic = 0x01;
constexpr std::uint8_t kReadIndividual = 0x04;
constexpr std::uint8_t kConformity = 0x81;   // 6.21: basic, stream and individual access
constexpr std::uint8_t kMoreFollows = 0xFF;  // 6.21: More Follows
constexpr std::size_t kResponseHeader = 7;   // fc, MEI, code, conformity, more, next id, count

}  // namespace

Dispatcher::Result Dispatcher::device_identification(std::span<const std::uint8_t> request,
                                                     std::span<std::uint8_t> out) {
  const std::uint8_t fc = request[0];
  // 6.19: other MEI types (0x0D, CANopen) are not served: illegal function.
  if (request.size() < 2 || request[1] != kMeiDeviceIdentification) {
    return {Result::Status::reply, exception_pdu(fc, Exception::illegal_function, out)};
  }
  if (request.size() != 4 || request[2] < kReadBasic || request[2] > kReadIndividual) {
    return {Result::Status::reply, exception_pdu(fc, Exception::illegal_data_value, out)};
  }
  const std::uint8_t code = request[2];
  std::uint8_t object = request[3];
  const auto count = static_cast<std::uint8_t>(objects_.size());
  if (code == kReadIndividual && object >= count) {
    // 6.21: individual access to an object that does not exist is exception 0x02.
    return {Result::Status::reply, exception_pdu(fc, Exception::illegal_data_address, out)};
  }
  // 6.21: in stream access, an unknown object id restarts at object 0; codes 02 and 03 ask for
  // more than this server has and are answered at its own level (the basic objects).
  if (object >= count) object = 0;
  const std::uint8_t last = code == kReadIndividual ? object : static_cast<std::uint8_t>(count - 1);

  out[0] = fc;
  out[1] = kMeiDeviceIdentification;
  out[2] = code;
  out[3] = kConformity;
  out[4] = 0;  // more follows: no
  out[5] = 0;  // next object id
  std::size_t at = kResponseHeader;
  std::uint8_t listed = 0;
  for (std::uint8_t id = object; id <= last; ++id) {
    const std::string& value = objects_[id];
    if (at + 2 + value.size() > kMaxPduSize) {  // does not fit: ask the client to continue
      out[4] = kMoreFollows;
      out[5] = id;
      break;
    }
    out[at] = id;
    out[at + 1] = static_cast<std::uint8_t>(value.size());
    std::copy(value.begin(), value.end(), out.begin() + static_cast<std::ptrdiff_t>(at + 2));
    at += 2 + value.size();
    ++listed;
  }
  out[6] = listed;
  return {Result::Status::reply, at};
}

}  // namespace drivegate::modbus
