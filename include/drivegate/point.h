// A point is one named value of a device, exposed in one Modbus table at a fixed address.
// Adapters describe their own points with PointSpec; the gateway lays them out after the common
// block (see docs/register-map.md) and encodes values into registers.
#pragma once

#include <cstdint>
#include <string>
#include <variant>
#include <vector>

namespace drivegate {

enum class Table : std::uint8_t { coil, discrete, input, holding };
enum class PointType : std::uint8_t { u16, i16, u32, i32, f32, string };
enum class Access : std::uint8_t { read, read_write };

// A label gives a name to a value (enums) or to a bit number (bit fields): the register map
// prints them so that a PLC programmer never has to guess what 3 means.
struct Label {
  std::string name;
  std::uint32_t value;
};

struct PointSpec {
  std::string name;  // snake_case, unique within the device
  Table table = Table::input;
  PointType type = PointType::u16;
  // Engineering value = register value x scale (f32 and string points use 1).
  double scale = 1.0;
  std::string unit;         // "rpm", "Hz", "bar", "degC", ... or empty
  std::string description;  // one line for the printed register map
  std::vector<Label> labels;
  bool bit_labels = false;  // labels name bit numbers rather than values
  // Registers a string point occupies (two characters each). Ignored for other types.
  std::uint16_t string_registers = 0;
  // Holding points only: the lowest and highest engineering value a write may carry. A write
  // outside is refused with exception 0x03 before the driver sees it.
  double min = 0.0;
  double max = 0.0;

  [[nodiscard]] Access access() const {
    return table == Table::holding || table == Table::coil ? Access::read_write : Access::read;
  }
  [[nodiscard]] std::uint16_t register_count() const {
    switch (type) {
      case PointType::u32:
      case PointType::i32:
      case PointType::f32:
        return 2;
      case PointType::string:
        return string_registers;
      default:
        return 1;
    }
  }
};

// A point's current engineering value. std::monostate means "not known yet" (served as 0, with
// the device's data_age and status telling the client how far to trust it).
using Value = std::variant<std::monostate, std::int64_t, double, std::string>;

inline double as_double(const Value& v) {
  if (const auto* i = std::get_if<std::int64_t>(&v)) return static_cast<double>(*i);
  if (const auto* d = std::get_if<double>(&v)) return *d;
  return 0.0;
}

}  // namespace drivegate
