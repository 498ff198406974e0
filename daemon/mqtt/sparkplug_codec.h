// Sparkplug B payloads <-> the protobuf bytes on the wire (spec 6.4, Appendix A; the schema is
// sparkplug_b.proto beside this file). Pure: bytes in, payloads out.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "mqtt/sparkplug.h"

namespace drivegate::sparkplug {

// The payload's protobuf encoding. Each metric's value goes into the field its datatype names
// (spec 6.4.16): Int8..Int32 and UInt8..UInt32 in int_value (signed ones as 32-bit two's
// complement), Int64 and UInt64 in long_value, Float, Double, Boolean, String in their own.
std::string encode(const Payload& payload);

// A received payload (NCMD, DCMD); nullopt and `why` when the bytes are not a Sparkplug payload.
// Metrics keep name, datatype and value; a metric known only by alias has an empty name.
std::optional<Payload> decode(std::string_view bytes, std::string& why);

}  // namespace drivegate::sparkplug
