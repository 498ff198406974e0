#include "device_id.h"

#include "codec.h"

namespace drivegate::modbus_device {
namespace {

// The reply's fixed part (Application Protocol 6.21, "Response"): function code, MEI type, read
// device id code, conformity level, more follows, next object id, number of objects.
constexpr std::size_t kHeader = 7;
// "More Follows": 0x00 no more objects, 0xFF more in a further transaction.
constexpr std::uint8_t kNoMore = 0x00;
constexpr std::uint8_t kMore = 0xFF;

}  // namespace

Bytes device_id_request(DeviceIdCode code, std::uint8_t first_object) {
  return {fc::encapsulated_interface, kMeiReadDeviceId, static_cast<std::uint8_t>(code),
          first_object};
}

std::optional<DeviceIdReply> parse_device_id_reply(ByteView pdu) {
  if (pdu.size() < kHeader || pdu[0] != fc::encapsulated_interface || pdu[1] != kMeiReadDeviceId) {
    return std::nullopt;
  }
  if (pdu[4] != kNoMore && pdu[4] != kMore) return std::nullopt;
  DeviceIdReply reply;
  reply.code = pdu[2];
  reply.conformity = pdu[3];
  reply.more_follows = pdu[4] == kMore;
  reply.next_object = pdu[5];
  const std::size_t count = pdu[6];
  std::size_t at = kHeader;
  for (std::size_t i = 0; i < count; ++i) {
    // Each object: its id, its length, then that many bytes.
    if (at + 2 > pdu.size() || at + 2 + pdu[at + 1] > pdu.size()) return std::nullopt;
    const std::size_t length = pdu[at + 1];
    DeviceIdObject object;
    object.id = pdu[at];
    object.value.assign(pdu.begin() + static_cast<std::ptrdiff_t>(at + 2),
                        pdu.begin() + static_cast<std::ptrdiff_t>(at + 2 + length));
    reply.objects.push_back(std::move(object));
    at += 2 + length;
  }
  if (at != pdu.size()) return std::nullopt;
  return reply;
}

}  // namespace drivegate::modbus_device
