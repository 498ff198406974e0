#include "profile_types.h"

#include <algorithm>
#include <cstdint>
#include <optional>
#include <string>

namespace drivegate::modbus_device {
namespace {

// A label's name: 1..40 characters of a-z, 0-9 and '_' (a metric's label value, a JSON key).
bool valid_label_name(std::string_view name) {
  return !name.empty() && name.size() <= 40 && std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
  });
}

// A label's key: decimal digits, or "0x" and hex digits (never octal: "010" is ten).
std::optional<std::uint64_t> label_key(std::string_view key) {
  int base = 10;
  if (key.size() > 2 && key[0] == '0' && (key[1] == 'x' || key[1] == 'X')) {
    key.remove_prefix(2);
    base = 16;
  }
  if (key.empty() || key.size() > 16) return std::nullopt;
  std::uint64_t v = 0;
  for (const char c : key) {
    int d = -1;
    if (c >= '0' && c <= '9') d = c - '0';
    if (base == 16 && c >= 'a' && c <= 'f') d = c - 'a' + 10;
    if (base == 16 && c >= 'A' && c <= 'F') d = c - 'A' + 10;
    if (d < 0) return std::nullopt;
    v = v * static_cast<std::uint64_t>(base) + static_cast<std::uint64_t>(d);
  }
  return v;
}

// The bits of a point's raw value: 16 a register.
unsigned bits_in(const ProfilePoint& p) {
  return p.type == ValueType::bit ? 1 : 16u * p.width();
}

// The highest value a `values` label may name: the type's largest (a signed type's largest
// positive), within the 32 bits a label carries.
std::uint64_t highest_value(const ProfilePoint& p) {
  switch (p.type) {
    case ValueType::bit:
      return 1;
    case ValueType::u16:
      return 0xFFFF;
    case ValueType::s16:
      return 0x7FFF;
    case ValueType::s32:
      return 0x7FFFFFFF;
    default:
      return 0xFFFFFFFF;
  }
}

}  // namespace

bool read_registers(TableReader& r, ProfilePoint& p, Diagnostics& diag) {
  if (p.type != ValueType::string) {
    if (r.node("registers") != nullptr) {
      diag.error(r.node("registers"), "point.registers",
                 "is a string point's length; a " +
                     std::string(kValueTypeNames[static_cast<std::size_t>(p.type)]) +
                     " has its own");
      return false;
    }
    return true;
  }
  const auto n = r.integer("registers", 1, kMaxStringRegisters, true);
  if (!n) return false;
  p.registers = static_cast<std::uint16_t>(*n);
  return true;
}

bool read_byte_order(TableReader& r, ProfilePoint& p, Diagnostics& diag) {
  const toml::node* bytes = r.node("byte_order");
  const toml::node* words = r.node("word_order");
  if (bytes == nullptr && words == nullptr) return true;
  if (bytes != nullptr && words != nullptr) {
    diag.error(words, "point.word_order",
               "is the shorthand of byte_order (big = abcd, little = cdab): give one of them");
    return false;
  }
  std::optional<ByteOrder> order;
  if (bytes != nullptr) {
    if (const auto b = r.choice("byte_order", kByteOrderNames, false)) {
      order = static_cast<ByteOrder>(*b);
    }
  } else if (const auto w = r.choice("word_order", kWordOrderNames, false)) {
    order = *w == 0 ? ByteOrder::abcd : ByteOrder::cdab;
  }
  if (!order) return false;
  const char* key = bytes != nullptr ? "point.byte_order" : "point.word_order";
  const toml::node* at = bytes != nullptr ? bytes : words;
  if (p.type == ValueType::string) {
    if (bytes == nullptr || (*order != ByteOrder::abcd && *order != ByteOrder::badc)) {
      diag.error(at, key,
                 "a string takes byte_order \"abcd\" (the first character in the high byte) or "
                 "\"badc\" (in the low byte)");
      return false;
    }
  } else if (p.width() != 2 && p.width() != 4) {
    diag.error(at, key,
               "applies to the 32- and 64-bit types (u32, s32, f32, u64, s64, f64) and strings");
    return false;
  }
  p.byte_order = *order;
  return true;
}

bool read_labels(TableReader& r, ProfilePoint& p, Diagnostics& diag) {
  const toml::node* bits = r.node("bits");
  const toml::node* values = r.node("values");
  if (bits == nullptr && values == nullptr) return true;
  const toml::node* at = bits != nullptr ? bits : values;
  const std::string key = bits != nullptr ? "point.bits" : "point.values";
  if (bits != nullptr && values != nullptr) {
    diag.error(values, "point.values", "a point has bits or values, not both");
    return false;
  }
  if (is_float(p.type) || p.type == ValueType::string) {
    diag.error(at, key,
               "names the values or bits of an integer point, not of a " +
                   std::string(kValueTypeNames[static_cast<std::size_t>(p.type)]));
    return false;
  }
  if (bits != nullptr && p.type == ValueType::bit) {
    diag.error(at, key, "a bit point has no bits but its own: name its values 0 and 1");
    return false;
  }
  if (p.scale != 1.0) {
    diag.error(at, key, "names raw values: a labelled point has scale 1");
    return false;
  }
  const auto* t = at->as_table();
  if (t == nullptr || t->empty()) {
    diag.error(at, key, "must be a table such as { 0 = \"ready\", 3 = \"fault\" }");
    return false;
  }
  const std::uint64_t highest = bits != nullptr ? bits_in(p) - 1 : highest_value(p);
  bool ok = true;
  std::vector<Label> labels;
  for (const auto& [k, v] : *t) {
    const std::string text(k.str());
    const auto number = label_key(text);
    if (!number || *number > highest) {
      diag.error(&v, key,
                 "key '" + text + "' must be " + (bits != nullptr ? "a bit number" : "a value") +
                     " 0.." + std::to_string(highest) + " of this " +
                     std::string(kValueTypeNames[static_cast<std::size_t>(p.type)]) +
                     " (decimal or \"0x..\")");
      ok = false;
      continue;
    }
    const auto* name = v.as_string();
    if (name == nullptr || !valid_label_name(name->get())) {
      diag.error(&v, key + "." + text,
                 "must be a name of 1..40 characters of a-z, 0-9 and '_'" +
                     (name != nullptr ? " (got '" + name->get() + "')" : std::string()));
      ok = false;
      continue;
    }
    const auto value = static_cast<std::uint32_t>(*number);
    const auto same_value = std::find_if(labels.begin(), labels.end(),
                                         [&](const Label& l) { return l.value == value; });
    const auto same_name = std::find_if(labels.begin(), labels.end(),
                                        [&](const Label& l) { return l.name == name->get(); });
    if (same_value != labels.end()) {
      diag.error(&v, key,
                 "key '" + text + "' is " + std::to_string(value) + ", named already ('" +
                     same_value->name + "')");
      ok = false;
    } else if (same_name != labels.end()) {
      diag.error(&v, key + "." + text,
                 "'" + name->get() + "' names " + std::to_string(same_name->value) +
                     " already: each name once");
      ok = false;
    } else {
      labels.push_back({name->get(), value});
    }
  }
  if (!ok) return false;
  std::sort(labels.begin(), labels.end(),
            [](const Label& a, const Label& b) { return a.value < b.value; });
  p.labels = std::move(labels);
  p.bit_labels = bits != nullptr;
  return true;
}

bool check_read_only(TableReader& r, ProfilePoint& p, Diagnostics& diag) {
  if (p.type != ValueType::string) return true;
  bool ok = true;
  if (p.access != PointAccess::read && r.node("access") != nullptr) {
    diag.error(r.node("access"), "point.access",
               "a string point is read-only: drivegate writes no strings (access = \"read\")");
    ok = false;
  }
  for (const char* limit : {"min", "max"}) {
    if (const toml::node* n = r.node(limit)) {
      diag.error(n, std::string("point.") + limit, "a string point is read-only: it has no limits");
      ok = false;
    }
  }
  p.access = PointAccess::read;
  return ok;
}

}  // namespace drivegate::modbus_device
