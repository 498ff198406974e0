// The access level a pass-through request needs (Device::forward): who may send a Modbus request
// PDU through to a slave the gateway does not interpret. The functions that only read need read;
// every other one, a function this table does not know included, may change something in the
// slave and needs maintain. A pass-through window has no command block, so there is nothing of
// operate's to reach: an operate client reads through it only.
#pragma once

#include <cstdint>
#include <span>

#include "gateway/session.h"

namespace drivegate {

AccessLevel forward_level(std::span<const std::uint8_t> pdu);

}  // namespace drivegate
