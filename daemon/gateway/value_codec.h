// Engineering values <-> Modbus registers, per point type and scale. 32-bit values take two
// registers and 64-bit values four, most significant first; strings two characters a register,
// first in the high byte.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include "drivegate/point.h"

namespace drivegate {

// Writes spec.register_count() registers. Values out of the type's range saturate; unknown
// values encode as NaN in a float, 0 in an integer (which has no value to spare).
void encode_value(const PointSpec& spec, const Value& value, std::span<std::uint16_t> out);

// A value as a number: NaN when it is not known (std::monostate).
double number_of(const Value& value);

// An integer (already in register units) into an integer point's registers (u64: below 0 is 0),
// saturating at the type's limits: what the common block's rows hold.
void encode_integer(PointType type, std::int64_t value, std::span<std::uint16_t> out);

// The engineering value a client wrote; nullopt when `in` is not a value of the point's type
// (a string point is not writable).
std::optional<Value> decode_value(const PointSpec& spec, std::span<const std::uint16_t> in);

// A string point's registers as text, as encode_value lays it: two characters a register, the
// first in the high byte, the NULs that pad it dropped from its end. The bytes are the device's:
// what shows them makes them printable (base/device_text.h).
std::string decode_text(std::span<const std::uint16_t> in);

// True for the values laid over several registers as one number (u32, i32, f32, u64, i64, f64):
// the ones a listener's word_order = "little" serves least significant word first. Strings are
// never reordered.
constexpr bool has_word_order(const PointSpec& spec) {
  return spec.type != PointType::string && registers_of(spec.type) > 1;
}

}  // namespace drivegate
