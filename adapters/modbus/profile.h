// A device profile: what a Modbus RTU / ASCII slave is, how to talk to it, which registers hold
// what, and how they map onto drivegate's common block (docs/profiles.md describes the file).
// parse_profile() reads the TOML text and validates it whole; it is pure (the caller reads the
// file), and every error names the file and line it is about.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "codec.h"
#include "drivegate/common.h"
#include "drivegate/line.h"
#include "drivegate/point.h"

namespace drivegate::modbus_device {

// A point's value type on the wire: one register (u16, s16), two (u32, s32, f32), four (u64,
// s64, f64; all in the point's byte order), `registers` of them (string: ASCII, two characters a
// register) or one coil / discrete input (bit). New types follow the older ones.
enum class ValueType : std::uint8_t { u16, s16, u32, s32, f32, bit, u64, s64, f64, string };
inline constexpr std::array<std::string_view, 10> kValueTypeNames = {
    "u16", "s16", "u32", "s32", "f32", "bit", "u64", "s64", "f64", "string"};
// True for the IEEE 754 types (f32, f64).
constexpr bool is_float(ValueType type) {
  return type == ValueType::f32 || type == ValueType::f64;
}
// Registers (or bits) a value of `type` occupies; a string its own `registers`.
constexpr std::uint16_t width_of(ValueType type, std::uint16_t registers = 0) {
  switch (type) {
    case ValueType::u32:
    case ValueType::s32:
    case ValueType::f32:
      return 2;
    case ValueType::u64:
    case ValueType::s64:
    case ValueType::f64:
      return 4;
    case ValueType::string:
      return registers;
    default:
      return 1;
  }
}
// The longest string point, in registers (128 characters).
inline constexpr std::uint16_t kMaxStringRegisters = 64;

// How a 32- or 64-bit value lies in its registers, its bytes named a (most significant), b, c,
// d...: abcd puts the most significant register first, high byte first in each (the default;
// Modbus itself says nothing of values wider than a register); cdab the least significant
// register first; badc and dcba the same with the two bytes of each register swapped. A string
// takes abcd (the first character in a register's high byte) or badc (in its low byte).
enum class ByteOrder : std::uint8_t { abcd, badc, cdab, dcba };
inline constexpr std::array<std::string_view, 4> kByteOrderNames = {"abcd", "badc", "cdab", "dcba"};
// The shorthand of the older profiles: word_order = "big" is abcd, "little" is cdab.
inline constexpr std::array<std::string_view, 2> kWordOrderNames = {"big", "little"};
constexpr bool words_reversed(ByteOrder o) {
  return o == ByteOrder::cdab || o == ByteOrder::dcba;
}
constexpr bool bytes_swapped(ByteOrder o) {
  return o == ByteOrder::badc || o == ByteOrder::dcba;
}

// Who may write a point through a Modbus listener: nobody (read), an operate or a maintain
// listener (operate), a maintain listener only (maintain; the default for a writable point).
enum class PointAccess : std::uint8_t { read, operate, maintain };
inline constexpr std::array<std::string_view, 3> kPointAccessNames = {"read", "operate",
                                                                      "maintain"};

// The device's request to write one register: FC 06 or FC 16 (Application Protocol 6.6, 6.12).
enum class WriteFunction : std::uint8_t { single, multiple };
inline constexpr std::array<std::string_view, 2> kWriteFunctionNames = {"single", "multiple"};

inline constexpr std::array<std::string_view, 2> kFramingNames = {"rtu", "ascii"};
// The tables a point may be in, by their profile names.
inline constexpr std::array<std::string_view, 4> kProfileTableNames = {"coil", "discrete", "input",
                                                                       "holding"};

// A profile's name, found as a file name: 1..64 characters of a-z, 0-9, '-' and '_'.
bool valid_profile_name(std::string_view name);

struct ProfilePoint {
  std::string name;
  Table table = Table::holding;
  std::uint16_t address = 0;  // the protocol address (0-based), as on the wire
  ValueType type = ValueType::u16;
  ByteOrder byte_order = ByteOrder::abcd;
  std::uint16_t registers = 0;  // a string's, 1..kMaxStringRegisters
  double scale = 1.0;           // engineering value = raw x scale
  std::string unit;
  std::string description;
  std::optional<double> min;  // engineering limits of a write
  std::optional<double> max;
  PointAccess access = PointAccess::read;
  std::uint32_t poll_ms = 0;  // 0: the device's poll interval
  bool trend = false;         // kept in the daemon's trends (PointSpec::trend)
  // Names of its values (an enumeration) or, with bit_labels, of its bits (a bit field): the
  // register map, JSON, page and /metrics show them (PointSpec::labels).
  std::vector<Label> labels;
  bool bit_labels = false;
  std::uint32_t line = 0;  // where the point is in the file, for messages
  // A u16 register point that is some of its register's bits: value = (raw & mask) >> the
  // mask's lowest set bit. Read-only; points whose masks do not overlap share a register.
  std::optional<std::uint16_t> mask;
  // A one-register holding point written with a user-defined function code of the device
  // (write_code = 0x41) laid out as FC 06: the "write without saving to EEPROM" of inverters
  // whose 0x06 saves every write. 0: the protocol's code (write_function).
  std::uint8_t write_code = 0;

  [[nodiscard]] std::uint16_t width() const { return width_of(type, registers); }
  [[nodiscard]] bool writable() const { return table == Table::holding || table == Table::coil; }
};

// Bits of a register point's value, any of them set meaning true:
// running = { point = "status_word", bit = 2 } or { ..., any_bit = [0, 1] }. A bit point's
// binding has the one bit 0 (the point's value).
// running = { point = "run_state", any_value = [1, 2] }: true when the point's value (a state
// code, not bits) is one of `values`; `bits` is then empty.
struct BitBinding {
  std::size_t point = 0;              // index into Profile::points
  std::vector<std::uint8_t> bits;     // 0..15, as the profile lists them, at least one
  std::vector<std::uint16_t> values;  // any_value: the codes that mean true

  // The bits as a mask of the point's value.
  [[nodiscard]] std::uint16_t mask() const {
    std::uint16_t m = 0;
    for (const std::uint8_t b : bits) m = static_cast<std::uint16_t>(m | (1u << b));
    return m;
  }
};
// A value written to a point: stop = { point = "control_word", value = 0x0006 }; to a coil
// (FC 05), 0 or 1. Or values written in order, each confirmed before the next: { point =
// "control_word", sequence = [0x047E, 0x047F] } (1..kMaxSequence), where an item may be a table
// naming its own point: { sequence = [{ point = "direction_coil", value = 1 }, { point =
// "run_coil", value = 1 }] }. `point` and `value` are the last step's: the command the drive ends
// in.
inline constexpr std::size_t kMaxSequence = 4;
struct ValueBinding {
  std::size_t point = 0;
  std::uint16_t value = 0;
  std::vector<std::uint16_t> sequence;  // what is written, in order; {value} for a single value
  std::vector<std::size_t> points;      // where each of `sequence` is written
};

// A device option the profile declares ([options.NAME]) and a device sets in [device.options]:
// a number within min..max (profile_options.h). `value` is the default (a required option's
// example) until the device's options are applied (apply_options, profile_options.h).
struct ProfileOption {
  std::string name;
  double value = 0;
  double default_value = 0;  // a required option's: its example
  // No default: the manual cites no factory value, so every device sets it; `example` is what
  // drivegate sim, profile check, [[example]] frames and the library test use.
  bool required = false;
  double min = 0;
  double max = 0;
  std::string unit;
  std::string description;
  std::uint32_t line = 0;
};

// rpm = the point's engineering value x factor + offset. Each is a product and quotient of terms,
// left to right ("120 / motor_poles"), a term a number, an option, or the difference of two of
// them in parentheses ("(max_frequency_hz - min_frequency_hz)"). A factor without terms is 1 (the
// point is in rpm).
struct RpmFactor {
  struct Operand {
    double number = 1;                  // when no option
    std::optional<std::size_t> option;  // index into Profile::options
  };
  struct Term {
    bool divide = false;
    Operand operand;
    std::optional<Operand> minus;  // (operand - minus)
  };
  std::vector<Term> terms;
  std::string text;  // as the profile wrote it
};
// A factor and an offset with a device's options: a point's engineering value and rpm, both ways.
struct RpmScale {
  double factor = 1.0;
  double offset = 0.0;
  [[nodiscard]] double rpm(double value) const { return value * factor + offset; }
  [[nodiscard]] double value(double rpm) const { return (rpm - offset) / factor; }
};
// A point's native values named as unified faults; values not in the map are `other`. Or, for a
// bit field (`bits`), its bits named: the lowest set bit that is named wins, a value with none of
// them set but some bit set is `other`, 0 is none.
struct FaultBinding {
  std::size_t point = 0;
  std::map<std::uint32_t, Fault> map;
  std::map<std::uint8_t, Fault> bits;  // not empty: the point is a bit field
  Fault other = Fault::other;
};

// How the common block maps onto the points. Every binding is optional: what a profile leaves
// out, the common block shows as unknown (and a command it cannot send is refused with 0x03).
struct CommonBindings {
  std::optional<std::size_t> speed_rpm;      // actual speed, scaled to rpm
  std::optional<std::size_t> setpoint_rpm;   // the speed reference, written in rpm
  RpmFactor speed_factor;                    // speed_rpm's rpm_factor
  RpmFactor setpoint_factor;                 // setpoint_rpm's rpm_factor
  std::optional<RpmFactor> speed_offset;     // speed_rpm's rpm_offset (only with rpm_factor)
  std::optional<RpmFactor> setpoint_offset;  // setpoint_rpm's rpm_offset
  std::optional<BitBinding> running;
  std::optional<BitBinding> fault;
  std::optional<FaultBinding> fault_code;
  std::optional<ValueBinding> stop;
  std::optional<ValueBinding> run_forward;
  std::optional<ValueBinding> run_reverse;
  std::optional<ValueBinding> reset_fault;
  // setpoint_rpm = { ..., runs = true }: the drive runs while its set value is not 0 and has no
  // run command (an EC fan, a BLDC driver). The gateway holds the setpoint while no run is in
  // force; run_forward writes it, stop writes 0 (docs/profiles.md, "A set value that runs").
  bool setpoint_runs = false;
};

struct LineSpec {
  std::uint32_t baud = 19200;    // Serial Line 2.5.1: 19200 is the required default
  Parity parity = Parity::even;  // Serial Line 2.5.1: even parity is the default
  std::uint8_t stop_bits = 1;
  Framing framing = Framing::rtu;
};

struct ModbusSpec {
  // Per read, the protocol's limits unless the device has lower ones (codec.h).
  std::uint16_t max_registers = kMaxReadRegisters;
  std::uint16_t max_bits = kMaxReadBits;
  std::uint16_t max_gap = 0;  // unused registers read through to join two blocks
  WriteFunction write = WriteFunction::single;
  std::uint32_t timeout_ms = 100;
};

// What the device answers to Read Device Identification (FC 0x2B / 0x0E, basic category,
// Application Protocol 6.21) when it is the device the profile describes: `drivegate scan`
// suggests the profile for a slave whose identification matches ([profile] identification).
struct ProfileIdentification {
  std::string vendor_name;   // object 0x00 VendorName, whole
  std::string product_code;  // object 0x01 ProductCode; a trailing '*' matches any rest
};

// A frame the device's manual prints, and what the profile must make of it ([[example]],
// profile_examples.h checks it).
struct ProfileExample {
  std::string request;  // hex as printed, with address and CRC (RTU) or as ASCII text
  std::string reply;    // optional for writes
  std::vector<std::pair<std::string, double>> expect;  // point name, engineering value
  std::string note;
  std::uint32_t line = 0;
};

// The common bindings `drivegate profile check` asks of a profile, which [common] unbound may
// leave out with a reason, in the common block's order.
inline constexpr std::array<std::string_view, 7> kUnboundable = {
    "speed_rpm", "setpoint_rpm", "running", "fault", "fault_code", "stop", "run_forward"};

struct Profile {
  std::string name;
  std::string description;
  std::string source;  // where the addresses come from: document, section, table
  std::optional<ProfileIdentification> identification;
  LineSpec line;
  ModbusSpec modbus;
  std::vector<ProfileOption> options;
  std::vector<ProfilePoint> points;
  CommonBindings common;
  std::vector<ProfileExample> examples;  // the manual's own frames ([[example]])
  // Common bindings the profile leaves out on purpose, and why ([common] unbound = { setpoint_rpm
  // = "a % of the range between minimum and maximum frequency" }): `drivegate profile check` does
  // not warn of them. Its keys are among kUnboundable.
  std::map<std::string, std::string, std::less<>> unbound;

  // The index of the point called `name`, if any.
  [[nodiscard]] std::optional<std::size_t> find(std::string_view point) const;
  // The index of the option called `name`, if any.
  [[nodiscard]] std::optional<std::size_t> find_option(std::string_view option) const;
  // Per point: whether the common block reads or commands through it (speed, setpoint, running,
  // fault, fault code, a command's points). The others are the device's own points, named in its
  // register map beside the common block's.
  [[nodiscard]] std::vector<bool> bound_to_common() const;
};

// The protocol's function code `p` is written with: 0x05 for a coil, 0x06 for one register where
// the profile says "single", 0x10 otherwise (Application Protocol 6.5, 6.6, 6.12).
std::uint8_t write_function(const ModbusSpec& m, const ProfilePoint& p);
// The code on the wire: the point's own write_code, else write_function's.
std::uint8_t write_code_of(const ModbusSpec& m, const ProfilePoint& p);
// The user-defined codes the profile's points are written with, each with its layout.
std::vector<CodeLayout> write_layouts(const Profile& profile);

// The profile in `text`, or every error found in it, each "SOURCE:LINE: key: what is wrong" as
// the daemon's own configuration errors read (drivegate/toml_reader.h). `source` names the file.
std::variant<Profile, std::vector<std::string>> parse_profile(std::string_view text,
                                                              const std::string& source);

}  // namespace drivegate::modbus_device
