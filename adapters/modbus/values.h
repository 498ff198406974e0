// A profile point's registers (or bit) <-> its engineering value: the type, the byte order of
// two- and four-register values and strings, the mask of a point that is some bits of its
// register, and the scale (engineering value = raw x scale). Pure.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "drivegate/point.h"
#include "profile.h"

namespace drivegate::modbus_device {

// The bits of register `word` that a masked point is, shifted down to bit 0 (the word itself for
// a point without a mask).
std::uint16_t masked(const ProfilePoint& p, std::uint16_t word);

// The raw number `words` hold for `p` (width() words; a bit point's one word is 0 or 1; a u64 or
// s64 beyond 2^53 as the nearest double; a string point's NaN).
double raw_of(const ProfilePoint& p, std::span<const std::uint16_t> words);

// A string point's text: two characters a register, the first in the high byte (badc: the low
// one); trailing NULs and spaces dropped, and any byte that is not printable ASCII (0x20..0x7E)
// shown as '?'.
std::string text_of(const ProfilePoint& p, std::span<const std::uint16_t> words);

// The engineering value of `words`: an integer when the point is an integer type with scale 1
// (a u64's 64 bits as they are, drivegate/point.h), a string for a string point, a double
// otherwise.
Value value_of(const ProfilePoint& p, std::span<const std::uint16_t> words);

// The words that carry engineering value `v` to `p` (width() words, in the point's byte order;
// for a masked point, the register with the value in the mask's bits and 0 elsewhere), or nothing
// when it is not a value of the point (out of its type's range once scaled, not a whole number for
// an integer type, a bit that is not 0 or 1, NaN or infinite, a 64-bit integer beyond +-2^53,
// which a double cannot say exactly, a string point).
std::optional<std::vector<std::uint16_t>> words_for(const ProfilePoint& p, double v);

// The words of a string point holding `text` (printable ASCII, at most two characters a
// register; NUL-padded), or nothing when it cannot.
std::optional<std::vector<std::uint16_t>> words_for_text(const ProfilePoint& p,
                                                         std::string_view text);

// The register-map type a point is served as: the width and signedness of its raw value (the
// register map carries the profile's scale beside it, so a PLC reads the device's own registers).
PointType served_type(const ProfilePoint& p);

}  // namespace drivegate::modbus_device
