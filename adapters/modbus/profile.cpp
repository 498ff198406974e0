#include "profile.h"

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <utility>

#include "drivegate/sim_text.h"
#include "drivegate/toml_reader.h"
#include "profile_examples.h"
#include "profile_options.h"
#include "profile_types.h"
#include "values.h"

namespace drivegate::modbus_device {
namespace {

// Point names are register-map names: snake_case, as every adapter's points.
bool valid_point_name(std::string_view name) {
  if (name.empty() || name.size() > 48 || !(name[0] >= 'a' && name[0] <= 'z')) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
  });
}

std::optional<Fault> fault_named(std::string_view name) {
  for (std::size_t i = 0; i < kFaultNames.size(); ++i) {
    if (kFaultNames[i] == name) return static_cast<Fault>(i);
  }
  return std::nullopt;
}

// An integer of one or two registers: a setpoint's or a bit field's type.
bool is_integer_of_two(ValueType t) {
  return t == ValueType::u16 || t == ValueType::s16 || t == ValueType::u32 || t == ValueType::s32;
}

// The line an error names ("SOURCE:LINE: ..."), 0 when it names none.
unsigned long line_in(const std::string& error, const std::string& source) {
  if (error.compare(0, source.size() + 1, source + ":") != 0) return 0;
  return std::strtoul(error.c_str() + source.size() + 1, nullptr, 10);
}

class Parser {
 public:
  explicit Parser(const std::string& source) : diag_(source) {}

  std::variant<Profile, std::vector<std::string>> run(std::string_view text,
                                                      const std::string& source) {
    toml::table root;
    try {
      root = toml::parse(text, source);
    } catch (const toml::parse_error& e) {
      diag_.error_at(static_cast<int>(e.source().begin.line), "", syntax_error_text(text, e));
      return std::move(diag_.errors);
    }
    {
      TableReader top(root, "", diag_);
      top.expect({"profile", "line", "modbus", "options", "point", "common", "example"});
      read_identity(top);
      read_line(top);
      read_modbus(top);
      bad_option_ = !read_profile_options(root, top, diag_, profile_);
      read_points(top);
      check_overlaps();
      read_common(top);
      read_profile_examples(root, top, diag_, profile_);
    }
    if (!diag_.errors.empty()) {
      // In file order, as a reader fixes them; the file-wide ones (line 0) first.
      std::stable_sort(diag_.errors.begin(), diag_.errors.end(),
                       [&](const std::string& a, const std::string& b) {
                         return line_in(a, source) < line_in(b, source);
                       });
      return std::move(diag_.errors);
    }
    return std::move(profile_);
  }

 private:
  void read_identity(TableReader& top) {
    top.read_table("profile", true, [&](TableReader& r) {
      r.expect({"name", "description", "source", "identification"});
      // Found by name in the profile folders: a file name's safe set ("example-vfd").
      if (auto name = r.file_name("name")) profile_.name = *name;
      profile_.description = r.string("description", false).value_or("");
      // Where every address comes from: a profile without it cannot be checked against anything.
      profile_.source = r.string("source", true).value_or("");
      if (const toml::node* n = r.node("identification")) read_identification(*n);
    });
  }

  // identification = { vendor_name = "...", product_code = "..." }: both, so that a scan never
  // suggests a profile for every product of a vendor (each has its own register map).
  void read_identification(const toml::node& n) {
    const auto* t = n.as_table();
    if (t == nullptr) {
      diag_.error(&n, "profile.identification",
                  "must be a table such as { vendor_name = \"...\", product_code = \"...\" }");
      return;
    }
    TableReader r(*t, "profile.identification", diag_);
    r.expect({"vendor_name", "product_code"});
    const auto vendor = r.string("vendor_name", true);
    const auto product = r.string("product_code", true);
    if (vendor && vendor->empty()) {
      diag_.error(r.node("vendor_name"), r.qualified("vendor_name"), "must not be empty");
      return;
    }
    if (product && (product->empty() || *product == "*")) {
      diag_.error(r.node("product_code"), r.qualified("product_code"),
                  "must name a product (a trailing '*' may stand for the rest of it)");
      return;
    }
    if (vendor && product) profile_.identification = ProfileIdentification{*vendor, *product};
  }

  void read_line(TableReader& top) {
    top.read_table("line", false, [&](TableReader& r) {
      r.expect({"baud", "parity", "stop_bits", "framing"});
      LineSpec& line = profile_.line;
      if (auto b = r.integer("baud", 300, 921600, false))
        line.baud = static_cast<std::uint32_t>(*b);
      if (auto p = r.choice("parity", kParityNames, false)) line.parity = static_cast<Parity>(*p);
      if (auto s = r.integer("stop_bits", 1, 2, false))
        line.stop_bits = static_cast<std::uint8_t>(*s);
      if (auto f = r.choice("framing", kFramingNames, false)) {
        line.framing = static_cast<Framing>(*f);
      }
    });
  }

  void read_modbus(TableReader& top) {
    top.read_table("modbus", false, [&](TableReader& r) {
      r.expect({"max_registers", "max_bits", "max_gap", "write", "timeout_ms"});
      ModbusSpec& m = profile_.modbus;
      if (auto v = r.integer("max_registers", 1, kMaxReadRegisters, false)) {
        m.max_registers = static_cast<std::uint16_t>(*v);
      }
      if (auto v = r.integer("max_bits", 1, kMaxReadBits, false)) {
        m.max_bits = static_cast<std::uint16_t>(*v);
      }
      if (auto v = r.integer("max_gap", 0, kMaxReadRegisters - 1, false))
        m.max_gap = static_cast<std::uint16_t>(*v);
      if (auto w = r.choice("write", kWriteFunctionNames, false)) {
        m.write = static_cast<WriteFunction>(*w);
      }
      if (auto v = r.integer("timeout_ms", 10, 10000, false)) {
        m.timeout_ms = static_cast<std::uint32_t>(*v);
      }
    });
  }

  void read_points(TableReader& top) {
    const bool any =
        top.read_each("point", [&](TableReader& r, const toml::table& t) { read_point(r, t); });
    if (!any) diag_.error_at(0, "point", "a profile needs at least one [[point]]");
  }

  void read_point(TableReader& r, const toml::table& t) {
    r.expect({"name", "table", "address", "type", "word_order", "scale", "unit", "description",
              "min", "max", "access", "poll_ms", "trend", "registers", "byte_order", "bits",
              "values", "mask", "write_code"});
    ProfilePoint p;
    p.line = static_cast<std::uint32_t>(t.source().begin.line);
    bool ok = true;
    if (auto name = r.string("name", true)) {
      p.name = *name;
      if (!valid_point_name(p.name)) {
        diag_.error(r.node("name"), "point.name",
                    "must be snake_case: a-z first, then a-z, 0-9, '_' (got '" + p.name + "')");
        ok = false;
      } else if (const auto other = profile_.find(p.name)) {
        diag_.error(r.node("name"), "point.name",
                    "'" + p.name + "' is defined twice (first on line " +
                        std::to_string(profile_.points[*other].line) + ")");
        ok = false;
      }
    } else {
      ok = false;
    }
    const auto table = r.choice("table", kProfileTableNames, true);
    if (table) p.table = static_cast<Table>(*table);
    const auto address = r.integer("address", 0, 65535, true);
    if (address) p.address = static_cast<std::uint16_t>(*address);
    const auto type = r.choice("type", kValueTypeNames, true);
    if (type) p.type = static_cast<ValueType>(*type);
    ok = ok && table && address && type;
    if (ok) ok = read_registers(r, p, diag_) && check_shape(r, p);
    if (ok) {
      ok = read_byte_order(r, p, diag_);
    } else {
      r.node("registers");
      r.node("byte_order");
      r.node("word_order");
    }
    if (auto s = r.number("scale", -1e9, 1e9, false)) {
      p.scale = *s;
      if (*s == 0.0) {
        diag_.error(r.node("scale"), "point.scale", "must not be 0");
        ok = false;
      }
    }
    p.unit = r.string("unit", false).value_or("");
    p.description = r.string("description", false).value_or("");
    ok = read_access_and_limits(r, p) && ok;
    if (ok) {
      ok = check_read_only(r, p, diag_) && read_labels(r, p, diag_);
    } else {
      r.node("bits");
      r.node("values");
    }
    if (ok) ok = read_mask(r, p);
    if (ok) {
      ok = read_write_code(r, p);
    } else {
      r.node("write_code");
    }
    if (auto v = r.integer("poll_ms", 10, 3600000, false))
      p.poll_ms = static_cast<std::uint32_t>(*v);
    if (ok)
      profile_.points.push_back(std::move(p));
    else
      had_bad_point_ = true;
  }

  // The type fits the table and the point fits the address space and the device's reads.
  bool check_shape(TableReader& r, const ProfilePoint& p) {
    const bool bit_table = is_bit_table(p.table);
    if (bit_table != (p.type == ValueType::bit)) {
      diag_.error(r.node("type"), "point.type",
                  bit_table ? "a coil or discrete input is of type bit"
                            : "type bit is for coils and discrete inputs; registers are u16, s16, "
                              "u32, s32, f32, u64, s64, f64 or string");
      return false;
    }
    if (std::uint32_t{p.address} + p.width() - 1 > 65535) {
      diag_.error(r.node("address"), "point.address",
                  "a point of " + std::to_string(p.width()) + " registers at " +
                      std::to_string(p.address) + " runs past the last register, 65535");
      return false;
    }
    if (!bit_table && p.width() > profile_.modbus.max_registers) {
      diag_.error(r.node("type"), "point.type",
                  "takes " + std::to_string(p.width()) +
                      " registers, more than the device reads "
                      "at once ([modbus] max_registers = " +
                      std::to_string(profile_.modbus.max_registers) + ")");
      return false;
    }
    return true;
  }

  bool read_access_and_limits(TableReader& r, ProfilePoint& p) {
    bool ok = true;
    p.trend = r.boolean("trend").value_or(false);
    p.access = p.writable() ? PointAccess::maintain : PointAccess::read;
    if (auto a = r.choice("access", kPointAccessNames, false)) {
      p.access = static_cast<PointAccess>(*a);
      if (!p.writable() && p.access != PointAccess::read) {
        diag_.error(r.node("access"), "point.access",
                    "an input register or discrete input cannot be written: access is read");
        ok = false;
      }
    }
    p.min = r.number("min", -1e12, 1e12, false);
    p.max = r.number("max", -1e12, 1e12, false);
    if ((p.min || p.max) && !p.writable()) {
      diag_.error(r.node(p.min ? "min" : "max"), p.min ? "point.min" : "point.max",
                  "limits a write: only holding registers and coils are written");
      ok = false;
    }
    if (p.min && p.max && *p.min > *p.max) {
      diag_.error(r.node("min"), "point.min", "is above point.max");
      ok = false;
    }
    return ok;
  }

  // mask = 0xFF00: some bits of a u16 register, read-only, so that a fault code in the high byte
  // and a state in the low byte are two points. Read-modify-write is not done: a write of some
  // bits would put back the others as they were read, maybe long ago.
  bool read_mask(TableReader& r, ProfilePoint& p) {
    const toml::node* n = r.node("mask");
    if (n == nullptr) return true;
    const auto mask = r.integer("mask", 0, 0xFFFF, true);
    if (!mask) return false;
    if (*mask == 0) {
      diag_.error(n, "point.mask", "must not be 0: a mask of no bits reads nothing");
      return false;
    }
    if (p.type != ValueType::u16) {
      diag_.error(n, "point.mask", "applies to u16 register points only");
      return false;
    }
    if (r.node("access") != nullptr && p.access != PointAccess::read) {
      diag_.error(r.node("access"), "point.access",
                  "a masked point is read-only (its register is not read, modified and written "
                  "back): access is read");
      return false;
    }
    if (p.min || p.max) {
      diag_.error(r.node(p.min ? "min" : "max"), p.min ? "point.min" : "point.max",
                  "limits a write: a masked point is read-only");
      return false;
    }
    p.mask = static_cast<std::uint16_t>(*mask);
    p.access = PointAccess::read;
    return true;
  }

  // write_code = 0x41: a user-defined code (Application Protocol 5) a writable one-register
  // holding point is written with, laid out as FC 06 (the manuals that give such a code for one
  // register lay it out so); a point written with FC 16 has none (no manual read lays out a code
  // for several registers the same way).
  bool read_write_code(TableReader& r, ProfilePoint& p) {
    const toml::node* n = r.node("write_code");
    if (n == nullptr) return true;
    const auto code = r.integer("write_code", 0, 255, true);
    if (!code) return false;
    if (!user_defined_code(static_cast<unsigned>(*code))) {
      diag_.error(n, "point.write_code",
                  "must be a user-defined function code (65..72 or 100..110, Application "
                  "Protocol 5) that the device's manual lays out as 6, got " +
                      std::to_string(*code));
      return false;
    }
    if (p.table != Table::holding || p.access == PointAccess::read) {
      diag_.error(n, "point.write_code",
                  "names how a point is written: only a writable holding register has one");
      return false;
    }
    if (write_function(profile_.modbus, p) != fc::write_single_register) {
      diag_.error(n, "point.write_code",
                  "is laid out as FC 06: only a one-register point under [modbus] write = "
                  "\"single\" has one (this one is written with FC 16)");
      return false;
    }
    p.write_code = static_cast<std::uint8_t>(*code);
    return true;
  }

  // Two points in one table may not share a register (or a bit), except one-register points
  // whose masks do not overlap.
  void check_overlaps() {
    std::vector<const ProfilePoint*> sorted;
    for (const auto& p : profile_.points) sorted.push_back(&p);
    std::sort(sorted.begin(), sorted.end(), [](const ProfilePoint* a, const ProfilePoint* b) {
      return std::tie(a->table, a->address, a->line) < std::tie(b->table, b->address, b->line);
    });
    for (std::size_t i = 0; i < sorted.size(); ++i) {
      const ProfilePoint& a = *sorted[i];
      for (std::size_t j = i + 1; j < sorted.size(); ++j) {
        const ProfilePoint& b = *sorted[j];
        if (a.table != b.table || std::uint32_t{a.address} + a.width() <= b.address) break;
        if (a.mask && b.mask && (*a.mask & *b.mask) == 0) continue;
        const ProfilePoint& later = a.line > b.line ? a : b;
        const ProfilePoint& earlier = a.line > b.line ? b : a;
        std::string why;
        if (a.mask && b.mask) {
          why = ": their masks share bits (" + hex(*a.mask & *b.mask, 4) + ")";
        } else if (a.mask || b.mask) {
          why = ": a register is shared only by points whose masks do not overlap";
        }
        diag_.error_at(static_cast<int>(later.line), "point",
                       "'" + later.name + "' overlaps '" + earlier.name + "' (line " +
                           std::to_string(earlier.line) + ") in the " +
                           std::string(kProfileTableNames[static_cast<std::size_t>(a.table)]) +
                           " table" + why);
      }
    }
  }

  // What a binding does with its point: reads it, writes a command's value to it (a
  // one-register holding point or a coil), or writes the setpoint (a holding point of one or two
  // registers, an integer or f32: FC 16 for two).
  enum class Use : std::uint8_t { read, command, setpoint };

  // A point named at `key` of `r`, which must exist and be of a kind `use` can use.
  std::optional<std::size_t> point_at(TableReader& r, std::string_view key, bool required,
                                      Use use) {
    const auto name = r.string(key, required);
    if (!name) return std::nullopt;
    const auto index = profile_.find(*name);
    if (!index) {
      // A point left out for its own error was reported already.
      if (!had_bad_point_) {
        diag_.error(r.node(key), r.qualified(key), "no point is called '" + *name + "'");
      }
      return std::nullopt;
    }
    const ProfilePoint& p = profile_.points[*index];
    if (use == Use::read) return index;
    if (p.mask) {
      diag_.error(r.node(key), r.qualified(key),
                  "'" + *name + "' is masked, so read-only: it cannot be written");
      return std::nullopt;
    }
    if (use == Use::command &&
        !(p.table == Table::coil || (p.table == Table::holding && p.width() == 1))) {
      diag_.error(r.node(key), r.qualified(key),
                  "'" + *name + "' must be a one-register holding point or a coil: it is written");
      return std::nullopt;
    }
    if (use == Use::setpoint &&
        !(p.table == Table::holding && (is_integer_of_two(p.type) || p.type == ValueType::f32))) {
      diag_.error(r.node(key), r.qualified(key),
                  "'" + *name +
                      "' must be a holding point of type u16, s16, u32, s32 or f32: it is written");
      return std::nullopt;
    }
    return index;
  }

  // speed_rpm = "speed_actual" (in rpm), or { point = "output_frequency", rpm_factor = "120 /
  // motor_poles" }: a point of a register table, and what its engineering value is multiplied by;
  // rpm_offset, beside rpm_factor only, what is added then.
  std::optional<std::size_t> rpm_point(TableReader& common, std::string_view key, Use use,
                                       RpmFactor& factor, std::optional<RpmFactor>& offset,
                                       bool* runs = nullptr) {
    const toml::node* n = common.node(key);
    if (n == nullptr || n->as_string() != nullptr) return register_point(common, key, use);
    const toml::table* t = inline_table(common, key);
    if (t == nullptr) return std::nullopt;
    TableReader r(*t, "common." + std::string(key), diag_);
    if (runs != nullptr) {
      r.expect({"point", "rpm_factor", "rpm_offset", "runs"});
      *runs = r.boolean("runs").value_or(false);
    } else {
      r.expect({"point", "rpm_factor", "rpm_offset"});
    }
    if (r.node("point") == nullptr) r.missing("point");
    const auto index = register_point(r, "point", use);
    const auto factor_text = r.string("rpm_factor", false);
    const auto offset_text = r.string("rpm_offset", false);
    if (offset_text && !factor_text) {
      diag_.error(r.node("rpm_offset"), r.qualified("rpm_offset"),
                  "goes only with rpm_factor (rpm = value x rpm_factor + rpm_offset)");
      return std::nullopt;
    }
    bool ok = true;
    const auto expression = [&](const std::optional<std::string>& text, const char* name,
                                auto parse) -> std::optional<RpmFactor> {
      if (!text) return std::nullopt;
      std::string why;
      if (auto e = parse(*text, profile_.options, why)) return e;
      ok = false;
      // An option left out for its own error was reported already.
      if (!bad_option_) diag_.error(r.node(name), r.qualified(name), "'" + *text + "' " + why);
      return std::nullopt;
    };
    if (auto f = expression(factor_text, "rpm_factor", parse_rpm_factor)) factor = std::move(*f);
    offset = expression(offset_text, "rpm_offset", parse_rpm_offset);
    return ok ? index : std::nullopt;
  }

  // speed_rpm = "speed_actual": a point of a register table; written (the setpoint), a holding
  // point of one or two registers (a two-register one goes with FC 16).
  std::optional<std::size_t> register_point(TableReader& r, std::string_view key, Use use) {
    const auto index = point_at(r, key, false, use);
    if (index && profile_.points[*index].type == ValueType::bit) {
      diag_.error(r.node(key), r.qualified(key), "must name a register point, not a bit");
      return std::nullopt;
    }
    if (index && profile_.points[*index].type == ValueType::string) {
      diag_.error(r.node(key), r.qualified(key), "must name a number, not a string point");
      return std::nullopt;
    }
    return index;
  }

  const toml::table* inline_table(TableReader& r, std::string_view key) {
    const toml::node* n = r.node(key);
    if (n == nullptr) return nullptr;
    const auto* t = n->as_table();
    if (t == nullptr) {
      diag_.error(n, r.qualified(key), "must be an inline table such as { point = \"...\", ... }");
    }
    return t;
  }

  std::optional<BitBinding> bit_binding(TableReader& common, std::string_view key) {
    const toml::table* t = inline_table(common, key);
    if (t == nullptr) return std::nullopt;
    TableReader r(*t, "common." + std::string(key), diag_);
    r.expect({"point", "bit", "any_bit", "any_value"});
    const auto index = point_at(r, "point", true, Use::read);
    const ProfilePoint* p = index ? &profile_.points[*index] : nullptr;
    if (p == nullptr) {
      r.node("bit");
      r.node("any_bit");
      r.node("any_value");
      return std::nullopt;
    }
    if (p->type == ValueType::bit) {
      for (const char* k : {"bit", "any_bit", "any_value"}) {
        if (r.node(k) != nullptr) {
          diag_.error(r.node(k), r.qualified(k),
                      "a bit point has no bits but its own: omit " + std::string(k));
          return std::nullopt;
        }
      }
      return BitBinding{*index, {0}, {}};
    }
    if (p->width() != 1) {
      r.node("bit");
      r.node("any_bit");
      r.node("any_value");
      diag_.error(r.node("point"), r.qualified("point"),
                  "'" + p->name + "' must be a one-register point (u16, s16) or a bit point");
      return std::nullopt;
    }
    if (const toml::node* codes = r.node("any_value")) {
      auto values = values_of(r, *p, codes);
      if (!values) return std::nullopt;
      return BitBinding{*index, {}, std::move(*values)};
    }
    auto bits = bits_of(r, *p);
    if (!bits) return std::nullopt;
    return BitBinding{*index, std::move(*bits), {}};
  }

  // any_value = [N, M, ...]: the state codes of a one-register point's value (a masked point's
  // value is its bits shifted down) that mean true; neither bit nor any_bit beside it.
  std::optional<std::vector<std::uint16_t>> values_of(TableReader& r, const ProfilePoint& p,
                                                      const toml::node* codes) {
    for (const char* k : {"bit", "any_bit"}) {
      if (r.node(k) != nullptr) {
        diag_.error(r.node(k), r.qualified(k), std::string(k) + " or any_value, not both");
        return std::nullopt;
      }
    }
    const auto* array = codes->as_array();
    if (array == nullptr || array->empty() || array->size() > 16) {
      diag_.error(codes, r.qualified("any_value"),
                  "must be a list of 1..16 values of the point, such as [1, 2]");
      return std::nullopt;
    }
    const std::uint16_t largest = masked(p, 0xFFFF);
    std::vector<std::uint16_t> values;
    for (const toml::node& n : *array) {
      const auto* i = n.as_integer();
      if (i == nullptr || i->get() < 0 || i->get() > largest) {
        diag_.error(&n, r.qualified("any_value"),
                    "values are numbers 0.." + std::to_string(largest) + " of '" + p.name + "'");
        return std::nullopt;
      }
      const auto v = static_cast<std::uint16_t>(i->get());
      if (std::find(values.begin(), values.end(), v) != values.end()) {
        diag_.error(&n, r.qualified("any_value"), std::to_string(v) + " is listed twice");
        return std::nullopt;
      }
      values.push_back(v);
    }
    return values;
  }

  // bit = N or any_bit = [N, M, ...]: bits of a one-register point's value (a masked point's
  // value is its bits shifted down, so a bit must be one of the mask's).
  std::optional<std::vector<std::uint8_t>> bits_of(TableReader& r, const ProfilePoint& p) {
    const toml::node* one = r.node("bit");
    const toml::node* any = r.node("any_bit");
    if (one != nullptr && any != nullptr) {
      diag_.error(any, r.qualified("any_bit"), "bit or any_bit, not both");
      return std::nullopt;
    }
    std::vector<std::pair<const toml::node*, std::int64_t>> listed;
    if (any == nullptr) {
      const auto bit = r.integer("bit", 0, 15, true);
      if (!bit) return std::nullopt;
      listed.emplace_back(one, *bit);
    } else {
      const auto* array = any->as_array();
      if (array == nullptr || array->empty() || array->size() > 16) {
        diag_.error(any, r.qualified("any_bit"),
                    "must be a list of 1..16 bit numbers 0..15, such as [0, 1]");
        return std::nullopt;
      }
      for (const toml::node& n : *array) {
        const auto* i = n.as_integer();
        if (i == nullptr || i->get() < 0 || i->get() > 15) {
          diag_.error(&n, r.qualified("any_bit"), "bits are numbers 0..15 of a register");
          return std::nullopt;
        }
        listed.emplace_back(&n, i->get());
      }
    }
    const std::uint16_t value_bits = masked(p, 0xFFFF);
    std::vector<std::uint8_t> bits;
    for (const auto& [n, bit] : listed) {
      const std::string key = any != nullptr ? "any_bit" : "bit";
      if (std::find(bits.begin(), bits.end(), bit) != bits.end()) {
        diag_.error(n, r.qualified(key), "bit " + std::to_string(bit) + " is listed twice");
        return std::nullopt;
      }
      if (((value_bits >> bit) & 1u) == 0) {
        diag_.error(n, r.qualified(key),
                    "bit " + std::to_string(bit) + " is not a bit of '" + p.name + "' (its mask " +
                        hex(*p.mask, 4) + " gives it the bits of " + hex(value_bits, 4) + ")");
        return std::nullopt;
      }
      bits.push_back(static_cast<std::uint8_t>(bit));
    }
    return bits;
  }

  // A coil is written ON or OFF (FC 05, Application Protocol 6.5): a command's value is 0 or 1.
  bool command_value_fits(const toml::node* at, const std::string& key, std::size_t point,
                          std::int64_t value) {
    const ProfilePoint& p = profile_.points[point];
    if (p.table != Table::coil || value <= 1) return true;
    diag_.error(
        at, key,
        "'" + p.name + "' is a coil: it is written 0 or 1 (got " + std::to_string(value) + ")");
    return false;
  }

  std::optional<ValueBinding> value_binding(TableReader& common, std::string_view key) {
    const toml::table* t = inline_table(common, key);
    if (t == nullptr) return std::nullopt;
    TableReader r(*t, "common." + std::string(key), diag_);
    r.expect({"point", "value", "sequence"});
    const toml::node* seq = r.node("sequence");
    // A sequence whose items are all tables names its points itself: `point` is then optional.
    const auto* items = seq != nullptr ? seq->as_array() : nullptr;
    const bool own_points =
        items != nullptr && !items->empty() &&
        std::all_of(items->begin(), items->end(), [](const toml::node& n) { return n.is_table(); });
    const auto index = point_at(r, "point", !own_points, Use::command);
    if (seq != nullptr && r.node("value") != nullptr) {
      diag_.error(seq, r.qualified("sequence"), "value or sequence, not both");
      return std::nullopt;
    }
    if (seq != nullptr) return sequence_binding(r, *seq, index);
    const auto value = r.integer("value", 0, 65535, true);
    if (!index || !value) return std::nullopt;
    if (!command_value_fits(r.node("value"), r.qualified("value"), *index, *value)) {
      return std::nullopt;
    }
    const auto v = static_cast<std::uint16_t>(*value);
    return ValueBinding{*index, v, {v}, {*index}};
  }

  // sequence = [0x047E, 0x047F], written to the binding's `point`, or items that name their own:
  // [{ point = "direction_coil", value = 1 }, { point = "run_coil", value = 1 }] (the two forms
  // may mix where the binding has a point). Each item's point is one a command can be written to.
  std::optional<ValueBinding> sequence_binding(TableReader& r, const toml::node& seq,
                                               std::optional<std::size_t> point) {
    const std::string usage = "must be 1.." + std::to_string(kMaxSequence) +
                              " values 0..65535 written in order, such as [0x047E, 0x047F], or "
                              "tables such as { point = \"run_coil\", value = 1 }";
    const auto* a = seq.as_array();
    if (a == nullptr || a->empty() || a->size() > kMaxSequence) {
      diag_.error(&seq, r.qualified("sequence"), usage);
      return std::nullopt;
    }
    ValueBinding b;
    bool ok = true;
    for (const toml::node& item : *a) {
      std::optional<std::size_t> at = point;
      std::optional<std::int64_t> value;
      if (const auto* t = item.as_table()) {
        TableReader ir(*t, r.qualified("sequence"), diag_);
        ir.expect({"point", "value"});
        at = point_at(ir, "point", true, Use::command);
        value = ir.integer("value", 0, 65535, true);
        if (at && value &&
            !command_value_fits(ir.node("value"), ir.qualified("value"), *at, *value)) {
          ok = false;
        }
      } else if (const auto* i = item.as_integer();
                 i != nullptr && i->get() >= 0 && i->get() <= 65535) {
        value = i->get();
        // Without the binding's point (missing or wrong: said already), the item has none.
        if (at && !command_value_fits(&item, r.qualified("sequence"), *at, *value)) ok = false;
      } else {
        diag_.error(&item, r.qualified("sequence"), usage);
        return std::nullopt;
      }
      if (!at || !value) {
        ok = false;
        continue;
      }
      b.sequence.push_back(static_cast<std::uint16_t>(*value));
      b.points.push_back(*at);
    }
    if (!ok) return std::nullopt;
    b.point = b.points.back();
    b.value = b.sequence.back();
    return b;
  }

  std::optional<Fault> fault_label(TableReader& r, const toml::node& n, std::string_view key) {
    const auto* s = n.as_string();
    const auto fault = s != nullptr ? fault_named(s->get()) : std::nullopt;
    if (fault == Fault::comm_lost) {
      // The gateway's own: the drive answered, so it is not what a native code can mean.
      diag_.error(&n, r.qualified(key), "comm_lost is the gateway's own fault, not a drive's");
      return std::nullopt;
    }
    if (!fault) {
      diag_.error(&n, r.qualified(key),
                  (s != nullptr ? "unknown fault label '" + s->get() + "'" : "must be a label") +
                      " (known: " + TableReader::names_text(kFaultNames) + ")");
    }
    return fault;
  }

  struct Labelled {
    const toml::node* at;
    std::int64_t key;
    Fault fault;
  };
  // fault_code.map or .bits: `KEY = "label"` pairs, keys decimal or "0x..", 0..`most` (`what`
  // says what a key is); nothing when any is wrong.
  std::optional<std::vector<Labelled>> labelled(TableReader& r, std::string_view name,
                                                std::int64_t most, const std::string& what) {
    const toml::node* m = r.node(name);
    const auto* map = m->as_table();
    if (map == nullptr) {
      diag_.error(m, r.qualified(name), "must be a table of " + what + " = \"label\"");
      return std::nullopt;
    }
    std::vector<Labelled> out;
    bool ok = true;
    for (const auto& [k, v] : *map) {
      const std::string key(k.str());
      std::int64_t value = -1;
      try {
        std::size_t used = 0;
        value = std::stoll(key, &used, 0);
        if (used != key.size()) value = -1;
      } catch (const std::exception&) {
        value = -1;
      }
      if (value < 0 || value > most) {
        diag_.error(&v, r.qualified(name), "key '" + key + "' must be " + what);
        ok = false;
        continue;
      }
      if (const auto f = fault_label(r, v, std::string(name) + "." + key)) {
        out.push_back({&v, value, *f});
      } else {
        ok = false;
      }
    }
    if (!ok) return std::nullopt;
    return out;
  }

  // fault_code.bits: the point is a bit field of trips, each bit named; a bit set is a trip, so
  // no bit is "none", and a masked point's bits are those of its mask.
  bool fault_bits(TableReader& r, FaultBinding& b) {
    const ProfilePoint& p = profile_.points[b.point];
    if (!is_integer_of_two(p.type)) {
      diag_.error(r.node("point"), r.qualified("point"),
                  "'" + p.name + "' is of type " +
                      std::string(kValueTypeNames[static_cast<std::size_t>(p.type)]) +
                      ": a bit field is a point of type u16, s16, u32 or s32");
      r.node("bits");
      return false;
    }
    const int width = 16 * p.width();
    const auto named =
        labelled(r, "bits", width - 1,
                 "a bit number 0.." + std::to_string(width - 1) + " of '" + p.name + "'");
    if (!named) return false;
    if (named->empty()) {
      diag_.error(r.node("bits"), r.qualified("bits"), "must name at least one bit");
      return false;
    }
    const std::uint16_t value_bits = masked(p, 0xFFFF);
    for (const auto& [at, bit, fault] : *named) {
      if (fault == Fault::none) {
        diag_.error(at, r.qualified("bits." + std::to_string(bit)),
                    "a bit set is a trip: none is what no bit set means");
        return false;
      }
      if (p.mask && ((value_bits >> bit) & 1u) == 0) {
        diag_.error(at, r.qualified("bits"),
                    "bit " + std::to_string(bit) + " is not a bit of '" + p.name + "' (its mask " +
                        hex(*p.mask, 4) + " gives it the bits of " + hex(value_bits, 4) + ")");
        return false;
      }
      b.bits[static_cast<std::uint8_t>(bit)] = fault;
    }
    return true;
  }

  std::optional<FaultBinding> fault_binding(TableReader& common) {
    const toml::table* t = inline_table(common, "fault_code");
    if (t == nullptr) return std::nullopt;
    TableReader r(*t, "common.fault_code", diag_);
    r.expect({"point", "map", "bits", "other"});
    FaultBinding b;
    const auto index = register_point(r, "point", Use::read);
    if (!index) {
      if (r.node("point") == nullptr) r.missing("point");
      r.node("map");
      r.node("bits");
      r.node("other");
      return std::nullopt;
    }
    b.point = *index;
    bool ok = true;
    if (r.node("map") != nullptr && r.node("bits") != nullptr) {
      diag_.error(r.node("bits"), r.qualified("bits"),
                  "map (the point's values) or bits (its bits), not both");
      ok = false;
    } else if (r.node("bits") != nullptr) {
      ok = fault_bits(r, b);
    } else if (r.node("map") != nullptr) {
      const auto named =
          labelled(r, "map", 0xFFFFFFFFLL, "a native fault value (0, 17, 0x11, ...)");
      if (named) {
        for (const auto& [at, value, fault] : *named)
          b.map[static_cast<std::uint32_t>(value)] = fault;
      }
      ok = named.has_value();
    }
    if (const toml::node* o = r.node("other")) {
      if (const auto f = fault_label(r, *o, "other"))
        b.other = *f;
      else
        ok = false;
    }
    if (!ok) return std::nullopt;
    return b;
  }

  void read_common(TableReader& top) {
    top.read_table("common", false, [&](TableReader& r, const toml::table* t) {
      r.expect({"speed_rpm", "setpoint_rpm", "running", "fault", "fault_code", "stop",
                "run_forward", "run_reverse", "reset_fault", "unbound"});
      read_unbound(r);
      CommonBindings& c = profile_.common;
      c.speed_rpm = rpm_point(r, "speed_rpm", Use::read, c.speed_factor, c.speed_offset);
      c.setpoint_rpm = rpm_point(r, "setpoint_rpm", Use::setpoint, c.setpoint_factor,
                                 c.setpoint_offset, &c.setpoint_runs);
      c.running = bit_binding(r, "running");
      c.fault = bit_binding(r, "fault");
      c.fault_code = fault_binding(r);
      c.stop = value_binding(r, "stop");
      c.run_forward = value_binding(r, "run_forward");
      c.run_reverse = value_binding(r, "run_reverse");
      c.reset_fault = value_binding(r, "reset_fault");
      if (c.setpoint_runs) check_set_value_runs(r);
      // A drive that can be started must be stoppable through the same profile.
      if ((c.run_forward || c.run_reverse) && !c.stop && r.node("stop") == nullptr) {
        diag_.error(t, "common",
                    "run_forward or run_reverse without stop: a profile that can start "
                    "the drive must say how to stop it");
      }
      refuse_own_intervals();
    });
  }

  // setpoint_rpm = { ..., runs = true }: the set value is the run command. run_forward writes the
  // setpoint held, so it is not bound apart, nor run_reverse (the set value is written 0 and up);
  // stop writes 0 to it unless the drive has a stop of its own (bound); 0 must be a value the point
  // takes.
  void check_set_value_runs(TableReader& r) {
    const CommonBindings& c = profile_.common;
    const char* const key = "setpoint_rpm.runs";
    for (const char* command : {"run_forward", "run_reverse"}) {
      if (r.node(command) == nullptr && profile_.unbound.count(command) == 0) continue;
      const toml::node* at = r.node(command) != nullptr ? r.node(command) : r.node("unbound");
      diag_.error(at, std::string("common.") + command,
                  "goes not with common." + std::string(key) +
                      " = true: the set value is the run command (run_forward writes the "
                      "setpoint to it)");
    }
    if (!c.setpoint_rpm) return;
    const ProfilePoint& p = profile_.points[*c.setpoint_rpm];
    if (p.width() != 1) {
      diag_.error(r.node("setpoint_rpm"), std::string("common.") + key,
                  "'" + p.name +
                      "' must be one register (u16 or s16): a reset first writes 0 "
                      "to it as one step of its sequence");
    }
    if ((p.min && *p.min > 0) || (p.max && *p.max < 0)) {
      diag_.error(r.node("setpoint_rpm"), std::string("common.") + key,
                  "'" + p.name + "' must take 0 (its min..max): stop writes 0 to it");
    }
  }

  // unbound = { setpoint_rpm = "why" }: bindings left out on purpose, each with its reason.
  void read_unbound(TableReader& r) {
    const toml::node* n = r.node("unbound");
    if (n == nullptr) return;
    const auto* t = n->as_table();
    if (t == nullptr) {
      diag_.error(n, "common.unbound", "must be a table of binding = \"why it is left out\"");
      return;
    }
    for (const auto& [k, v] : *t) {
      const std::string key(k.str());
      const auto* why = v.as_string();
      if (std::find(kUnboundable.begin(), kUnboundable.end(), key) == kUnboundable.end()) {
        diag_.error(
            &v, "common.unbound." + key,
            "not a binding the check asks for (" + TableReader::names_text(kUnboundable) + ")");
      } else if (why == nullptr || why->get().empty()) {
        diag_.error(&v, "common.unbound." + key, "must say why it is left out");
      } else if (r.node(key) != nullptr) {
        diag_.error(&v, "common.unbound." + key, "is bound: remove one of them");
      } else {
        profile_.unbound.emplace(key, why->get());
      }
    }
  }

  // The common block is the drive's state as of its data age: every point bound to it is polled
  // at the device's poll_ms, so a point of its own interval there is an error.
  void refuse_own_intervals() {
    const CommonBindings& c = profile_.common;
    std::vector<std::pair<std::size_t, std::string_view>> bound;
    if (c.speed_rpm) bound.emplace_back(*c.speed_rpm, "speed_rpm");
    if (c.setpoint_rpm) bound.emplace_back(*c.setpoint_rpm, "setpoint_rpm");
    if (c.running) bound.emplace_back(c.running->point, "running");
    if (c.fault) bound.emplace_back(c.fault->point, "fault");
    if (c.fault_code) bound.emplace_back(c.fault_code->point, "fault_code");
    for (const auto& [v, key] :
         {std::pair{c.stop, "stop"}, std::pair{c.run_forward, "run_forward"},
          std::pair{c.run_reverse, "run_reverse"}, std::pair{c.reset_fault, "reset_fault"}}) {
      if (!v) continue;
      for (const std::size_t point : v->points) bound.emplace_back(point, key);
    }
    std::vector<bool> told(profile_.points.size(), false);
    for (const auto& [index, key] : bound) {
      const ProfilePoint& p = profile_.points[index];
      if (p.poll_ms == 0 || told[index]) continue;
      told[index] = true;
      diag_.error_at(static_cast<int>(p.line), "point.poll_ms",
                     "'" + p.name + "' is bound to the common block (common." + std::string(key) +
                         "), which is polled at the device's poll_ms: remove poll_ms");
    }
  }

  Diagnostics diag_;
  Profile profile_;
  bool had_bad_point_ = false;
  bool bad_option_ = false;  // an [options.NAME] left out for its error
};

}  // namespace

bool valid_profile_name(std::string_view name) {
  return valid_file_name(name);
}

std::optional<std::size_t> Profile::find(std::string_view point) const {
  return index_of(points, point);
}

std::optional<std::size_t> Profile::find_option(std::string_view option) const {
  return index_of(options, option);
}

std::vector<bool> Profile::bound_to_common() const {
  std::vector<bool> bound(points.size(), false);
  for (const auto& p : {common.speed_rpm, common.setpoint_rpm}) {
    if (p) bound[*p] = true;
  }
  for (const auto& b : {common.running, common.fault}) {
    if (b) bound[b->point] = true;
  }
  if (common.fault_code) bound[common.fault_code->point] = true;
  for (const auto& v : {common.stop, common.run_forward, common.run_reverse, common.reset_fault}) {
    if (!v) continue;
    for (const std::size_t p : v->points) bound[p] = true;
  }
  return bound;
}

std::uint8_t write_function(const ModbusSpec& m, const ProfilePoint& p) {
  if (p.table == Table::coil) return fc::write_single_coil;
  if (p.width() == 1 && m.write == WriteFunction::single) return fc::write_single_register;
  return fc::write_multiple_registers;
}

std::uint8_t write_code_of(const ModbusSpec& m, const ProfilePoint& p) {
  return p.write_code != 0 ? p.write_code : write_function(m, p);
}

std::vector<CodeLayout> write_layouts(const Profile& profile) {
  std::vector<CodeLayout> layouts;
  for (const ProfilePoint& p : profile.points) {
    if (p.write_code == 0) continue;
    const bool known = std::any_of(layouts.begin(), layouts.end(),
                                   [&](const CodeLayout& l) { return l.code == p.write_code; });
    if (!known) layouts.push_back({p.write_code, write_function(profile.modbus, p)});
  }
  return layouts;
}

std::variant<Profile, std::vector<std::string>> parse_profile(std::string_view text,
                                                              const std::string& source) {
  return Parser(source).run(text, source);
}

}  // namespace drivegate::modbus_device
