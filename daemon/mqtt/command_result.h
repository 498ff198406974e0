// A DCMD's outcome as `Command/Last Result` publishes it (docs/mqtt.md, "Commands"): "ok", or the
// Modbus exception, code and name, that the same write gets from a Modbus client's listener, so a
// host that watches both sees one vocabulary. Written out here, since the MQTT side does not link
// the Modbus server; tests/modbus/outcome_test.cpp holds every text to the Modbus edge's table
// (modbus/modbus_exception.h).
#pragma once

#include <array>
#include <string_view>

#include "gateway/outcome.h"

namespace drivegate::mqtt {

// In Outcome's order.
inline constexpr std::array<std::string_view, kOutcomeNames.size()> kCommandResults = {
    "ok",
    "exception 0x0A (gateway path unavailable)",
    "exception 0x02 (illegal data address)",
    "exception 0x01 (illegal function)",
    "exception 0x03 (illegal data value)",
    "exception 0x06 (server device busy)",
    "exception 0x04 (server device failure)",
    "exception 0x0B (gateway target device failed to respond)",
};
constexpr std::string_view command_result(Outcome o) {
  return kCommandResults.at(static_cast<std::size_t>(o));
}

}  // namespace drivegate::mqtt
