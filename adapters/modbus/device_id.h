// Read Device Identification, function 0x2B with MEI type 0x0E ("MODBUS Application Protocol
// Specification V1.1b3", here "Application Protocol", 6.21): the request a master sends and the
// reply it gets back, as PDUs (codec.h frames them). Pure: bytes in, objects out. `drivegate scan`
// asks every slave it finds for its basic identification with it.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "drivegate/bytes.h"

namespace drivegate::modbus_device {

// The MEI type of Read Device Identification (Application Protocol 6.21, and Annex "MEI types").
inline constexpr std::uint8_t kMeiReadDeviceId = 0x0E;

// What a request asks for (6.21, "Read Device ID code"): a category read as a stream, from an
// object on (basic 01, regular 02, extended 03), or one object alone (specific 04).
enum class DeviceIdCode : std::uint8_t {
  basic = 0x01,
  regular = 0x02,
  extended = 0x03,
  specific = 0x04
};

// The objects of the basic and regular categories (6.21, "Object Id" table): 0x00..0x02 are
// basic and mandatory, 0x03..0x06 regular and optional; 0x80..0xFF are the device's own.
namespace device_id_object {
inline constexpr std::uint8_t vendor_name = 0x00;
inline constexpr std::uint8_t product_code = 0x01;
inline constexpr std::uint8_t major_minor_revision = 0x02;
}  // namespace device_id_object
inline constexpr std::array<std::string_view, 7> kDeviceIdObjectNames = {
    "VendorName",  "ProductCode", "MajorMinorRevision", "VendorUrl",
    "ProductName", "ModelName",   "UserApplicationName"};
// The specification's name of object `id`, or "" for the reserved and the device's own.
constexpr std::string_view device_id_object_name(std::uint8_t id) {
  return id < kDeviceIdObjectNames.size() ? kDeviceIdObjectNames[id] : std::string_view();
}

// The request PDU: 0x2B, 0x0E, the read device id code, the first object wanted.
Bytes device_id_request(DeviceIdCode code, std::uint8_t first_object);

struct DeviceIdObject {
  std::uint8_t id = 0;
  std::string value;  // as the device sent it (the specification says ASCII string; not checked)
  friend bool operator==(const DeviceIdObject&, const DeviceIdObject&) = default;
};

struct DeviceIdReply {
  std::uint8_t code = 0;        // the read device id code, echoed
  std::uint8_t conformity = 0;  // the categories the device supports (0x01..0x03, 0x81..0x83)
  bool more_follows = false;    // "More Follows" 0xFF: ask again from next_object for the rest
  std::uint8_t next_object = 0;
  std::vector<DeviceIdObject> objects;
};

// A reply PDU (function code first), or nullopt when it is not a well-formed one: another
// function or MEI type, a "More Follows" other than 0x00 and 0xFF, or objects that do not fill
// the PDU exactly as their count and lengths say. An exception reply is not one: see
// exception_code() in codec.h.
std::optional<DeviceIdReply> parse_device_id_reply(ByteView pdu);

}  // namespace drivegate::modbus_device
