// A point is one named value of a device, exposed in one Modbus table at a fixed address.
// Adapters describe their own points with PointSpec; the gateway lays them out after the common
// block (see docs/register-map.md) and encodes values into registers.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace drivegate {

enum class Table : std::uint8_t { coil, discrete, input, holding };
// 64-bit values (u64, i64, f64) take four registers; their names follow the older ones so that
// a type's number never changes.
enum class PointType : std::uint8_t { u16, i16, u32, i32, f32, string, u64, i64, f64 };
// Their names in the printed register map, in enum order.
inline constexpr std::array<std::string_view, 4> kTableNames = {"coil", "discrete", "input",
                                                                "holding"};
inline constexpr std::array<std::string_view, 9> kPointTypeNames = {
    "u16", "i16", "u32", "i32", "f32", "string", "u64", "i64", "f64"};
constexpr std::string_view to_string(Table t) {
  return kTableNames.at(static_cast<std::size_t>(t));
}
constexpr std::string_view to_string(PointType t) {
  return kPointTypeNames.at(static_cast<std::size_t>(t));
}
enum class Access : std::uint8_t { read, read_write };

// Registers a value of `type` takes: 32-bit values two, 64-bit ones four, a string its own
// count.
constexpr std::uint16_t registers_of(PointType type, std::uint16_t string_registers = 0) {
  switch (type) {
    case PointType::u32:
    case PointType::i32:
    case PointType::f32:
      return 2;
    case PointType::u64:
    case PointType::i64:
    case PointType::f64:
      return 4;
    case PointType::string:
      return string_registers;
    default:
      return 1;
  }
}

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
  // Engineering value = register value x scale (f32, f64 and string points use 1).
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
  // Holding points and coils only: who may write it (README, "Listeners and access"). An
  // adapter's own points are maintain's; one may open a point to operate clients (a profile's
  // access = "operate") or close it to writes altogether (access = "read": served read-only).
  enum class WriteLevel : std::uint8_t { maintain, operate, none };
  WriteLevel write_level = WriteLevel::maintain;
  // Worth a trend (history/trend_store.h: /api/v1/trends, the page's charts): a measurement
  // that tells what the machine did before a trip (currents, voltages, pressures, temperatures,
  // power), not a code or a counter.
  bool trend = false;

  // Modifiers for building point lists: input_point("speed", ...).scaled(0.1).
  PointSpec& scaled(double s) {
    scale = s;
    return *this;
  }
  PointSpec& limited(double lo, double hi) {
    min = lo;
    max = hi;
    return *this;
  }
  PointSpec& trended() {
    trend = true;
    return *this;
  }
  PointSpec& named_values(std::vector<Label> l) {
    labels = std::move(l);
    bit_labels = false;
    return *this;
  }
  PointSpec& named_bits(std::vector<Label> l) {
    labels = std::move(l);
    bit_labels = true;
    return *this;
  }

  [[nodiscard]] Access access() const {
    const bool writable_table = table == Table::holding || table == Table::coil;
    return writable_table && write_level != WriteLevel::none ? Access::read_write : Access::read;
  }
  [[nodiscard]] std::uint16_t register_count() const;
  // How many addresses of its table the point takes: one bit, or its registers.
  [[nodiscard]] std::uint16_t address_count() const;
};

// Coils and discrete inputs hold one bit per address, whatever a point's value type; input and
// holding registers a 16-bit word each.
constexpr bool is_bit_table(Table t) {
  return t == Table::coil || t == Table::discrete;
}

inline std::uint16_t PointSpec::register_count() const {
  return registers_of(type, string_registers);
}

inline std::uint16_t PointSpec::address_count() const {
  return is_bit_table(table) ? 1 : register_count();
}

// Builders for the common shapes; the modifiers above add scale, limits and labels.
inline PointSpec make_point(Table table, PointType type, std::string name, std::string unit,
                            std::string description) {
  PointSpec p;
  p.name = std::move(name);
  p.table = table;
  p.type = type;
  p.unit = std::move(unit);
  p.description = std::move(description);
  return p;
}
inline PointSpec input_point(std::string name, PointType type, std::string unit,
                             std::string description) {
  return make_point(Table::input, type, std::move(name), std::move(unit), std::move(description));
}
inline PointSpec holding_point(std::string name, PointType type, std::string unit,
                               std::string description) {
  return make_point(Table::holding, type, std::move(name), std::move(unit), std::move(description));
}
inline PointSpec string_point(std::string name, std::uint16_t registers, std::string description) {
  PointSpec p = input_point(std::move(name), PointType::string, "", std::move(description));
  p.string_registers = registers;
  return p;
}

// Labels for values (or bit numbers) 0, 1, 2 ... named in that order.
template <class Names>
std::vector<Label> labels_in_order(const Names& names) {
  std::vector<Label> out;
  out.reserve(std::size(names));
  std::uint32_t value = 0;
  for (const auto& n : names) out.push_back({std::string(n), value++});
  return out;
}

// A point's current engineering value. std::monostate means "not known yet" (served as 0, with
// the device's data_age and status telling the client how far to trust it). A u64 point's
// std::int64_t holds its 64 bits as they are: one below 0 stands for a value of 2^63 or more, so
// that the registers carry the device's exact bits (decode_value gives such a value back as the
// nearest double).
using Value = std::variant<std::monostate, std::int64_t, double, std::string>;

inline double as_double(const Value& v) {
  if (const auto* i = std::get_if<std::int64_t>(&v)) return static_cast<double>(*i);
  if (const auto* d = std::get_if<double>(&v)) return *d;
  return 0.0;
}

}  // namespace drivegate
