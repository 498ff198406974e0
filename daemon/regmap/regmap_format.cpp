#include "regmap_format.h"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <sstream>

#include "base/json.h"
#include "gateway/device.h"  // required_level

namespace drivegate {
namespace {

std::string number(double v) {
  std::ostringstream out;
  out.precision(10);
  out << v;
  return out.str();
}

// Coils and discrete inputs are single bits on the wire, whatever the point's value type.
std::string type_of(const MappedPoint& p) {
  return is_bit_table(p.spec.table) ? std::string("bit") : std::string(to_string(p.spec.type));
}

// Who may write the point, as the listeners' `access` levels name it: "operate" (the command
// block, and points the adapter opens to operate), "maintain" (every other writable point), or
// "read" (read-only: every level reads it, none writes it).
std::string_view access_of(const MappedPoint& p) {
  return p.spec.access() == Access::read_write ? to_string(required_level(p))
                                               : to_string(AccessLevel::read);
}

// The Modicon order of the tables: their reference's leading digit.
int table_rank(Table t) {
  switch (t) {
    case Table::coil:
      return 0;
    case Table::discrete:
      return 1;
    case Table::input:
      return 3;
    case Table::holding:
      return 4;
  }
  return 5;
}

// A device's points in reference order: table by table, then by address.
std::vector<const MappedPoint*> in_reference_order(const RegisterMap& map) {
  std::vector<const MappedPoint*> out;
  for (const auto& p : map.points()) out.push_back(&p);
  std::stable_sort(out.begin(), out.end(), [](const MappedPoint* a, const MappedPoint* b) {
    const int ra = table_rank(a->spec.table);
    const int rb = table_rank(b->spec.table);
    return ra != rb ? ra < rb : a->address < b->address;
  });
  return out;
}

// 5-digit references reach address 9998 (x9999); a point on any register past it, in any
// device, makes the whole map 6-digit, so one printout never mixes the two.
int reference_digits(const std::vector<DeviceRegisters>& devices) {
  for (const auto& dev : devices) {
    for (const auto& p : dev.map.points()) {
      const unsigned span = p.spec.address_count();
      if (p.address + std::max(span, 1u) - 1 > 9998) return 6;
    }
  }
  return 5;
}

// What a listener's word order means for a reader of the map, and mbpoll's switch for it.
std::string word_order_text(WordOrder w) {
  return w == WordOrder::big ? "big: high word first (mbpoll -B)"
                             : "little: low word first (mbpoll without -B)";
}

std::string labels_text(const PointSpec& s) {
  std::string out;
  for (const auto& l : s.labels) {
    if (!out.empty()) out += "; ";
    out += (s.bit_labels ? "bit " : "") + std::to_string(l.value) + "=" + l.name;
  }
  return out;
}

std::string csv_field(std::string_view s) {
  if (s.find_first_of(",\"\n") == std::string_view::npos) return std::string(s);
  std::string out = "\"";
  for (const char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string md_field(std::string_view s) {
  std::string out;
  for (const char c : s) out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

// The points a PLC reads at the device's unit: none through a pass-through window.
std::vector<const MappedPoint*> served(const DeviceRegisters& dev) {
  return dev.forwards ? std::vector<const MappedPoint*>{} : in_reference_order(dev.map);
}

// A device option's value as JSON: a number, true / false, a string, a list of strings.
std::string option_json(const OptionValue& v) {
  if (const auto* i = std::get_if<std::int64_t>(&v)) return std::to_string(*i);
  if (const auto* d = std::get_if<double>(&v)) {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, *d);
    return {buf, r.ptr};
  }
  if (const auto* b = std::get_if<bool>(&v)) return *b ? "true" : "false";
  if (const auto* s = std::get_if<std::string>(&v)) return json_string(*s);
  std::string out = "[";
  for (const auto& item : std::get<std::vector<std::string>>(v)) {
    out += (out.size() > 1 ? ", " : "") + json_string(item);
  }
  return out + "]";
}

// The options the device runs with, its adapter's defaults filled in (a profile's own options
// among them): {"profile": "abb-acs580", "motor_poles": 2, ...}.
std::string options_json(const DeviceConfig& device) {
  std::string out = "{";
  for (const auto& [name, value] : device.options.all()) {
    out += (out.size() > 1 ? ", " : "") + json_string(name) + ": " + option_json(value);
  }
  return out + "}";
}

std::string to_json(const std::vector<DeviceRegisters>& devices,
                    const std::vector<ServedOn>& listeners) {
  const int digits = reference_digits(devices);
  std::ostringstream out;
  out << "{\"devices\": [";
  for (std::size_t d = 0; d < devices.size(); ++d) {
    const auto& dev = devices[d];
    out << (d ? ",\n" : "\n") << "  {\"unit_id\": " << int{dev.device->unit_id}
        << ", \"name\": " << json_string(dev.device->name)
        << ", \"adapter\": " << json_string(dev.device->adapter)
        << (dev.forwards ? ", \"passthrough\": true" : "")
        << ", \"options\": " << options_json(*dev.device) << ", \"points\": [";
    const auto points = served(dev);
    for (std::size_t i = 0; i < points.size(); ++i) {
      const auto& p = *points[i];
      out << (i ? ",\n" : "\n") << "    {\"name\": " << json_string(p.spec.name)
          << ", \"table\": \"" << to_string(p.spec.table) << "\", \"address\": " << p.address
          << ", \"reference\": \"" << modicon_reference(p.spec.table, p.address, digits)
          << "\", \"type\": \"" << type_of(p) << "\", \"scale\": " << number(p.spec.scale)
          << ", \"unit\": " << json_string(p.spec.unit) << ", \"access\": \"" << access_of(p)
          << "\", \"description\": " << json_string(p.spec.description);
      if (p.spec.type == PointType::string) out << ", \"registers\": " << p.spec.register_count();
      out << ", \"labels\": {";
      for (std::size_t l = 0; l < p.spec.labels.size(); ++l) {
        out << (l ? ", " : "") << json_string(p.spec.labels[l].name) << ": "
            << p.spec.labels[l].value;
      }
      out << "}";
      if (p.spec.bit_labels) out << ", \"labels_are_bits\": true";
      out << "}";
    }
    out << "\n  ]}";
  }
  out << "\n],\n\"listeners\": [";
  for (std::size_t i = 0; i < listeners.size(); ++i) {
    out << (i ? ",\n" : "\n") << "  {\"address\": " << json_string(listeners[i].listener)
        << ", \"word_order\": \"" << to_string(listeners[i].word_order) << "\"}";
  }
  out << "\n]}\n";
  return out.str();
}

std::string to_csv(const std::vector<DeviceRegisters>& devices) {
  std::ostringstream out;
  const int digits = reference_digits(devices);
  out << "unit_id,device,adapter,name,table,address,reference,type,registers,scale,unit,access,"
         "description,labels\n";
  for (const auto& dev : devices) {
    for (const MappedPoint* point : served(dev)) {
      const auto& p = *point;
      out << int{dev.device->unit_id} << "," << csv_field(dev.device->name) << ","
          << csv_field(dev.device->adapter) << "," << csv_field(p.spec.name) << ","
          << to_string(p.spec.table) << "," << p.address << ","
          << modicon_reference(p.spec.table, p.address, digits) << "," << type_of(p) << ","
          << p.spec.register_count() << "," << number(p.spec.scale) << "," << csv_field(p.spec.unit)
          << "," << access_of(p) << "," << csv_field(p.spec.description) << ","
          << csv_field(labels_text(p.spec)) << "\n";
    }
  }
  return out.str();
}

std::string to_markdown(const std::vector<DeviceRegisters>& devices,
                        const std::vector<ServedOn>& listeners) {
  const int digits = reference_digits(devices);
  const std::string c0 = modicon_reference(Table::coil, 0, digits);
  const std::string d0 = modicon_reference(Table::discrete, 0, digits);
  const std::string i0 = modicon_reference(Table::input, 0, digits);
  const std::string h0 = modicon_reference(Table::holding, 0, digits);
  std::ostringstream out;
  out << "# drivegate register map\n\n"
         "Addresses are 0-based, as on the wire; beside each is its Modicon reference: coils "
      << c0 << " + address, discrete inputs " << d0 << " + address, input registers " << i0
      << " + address, holding registers " << h0
      << " + address (mbpoll's `-r` is the reference without its table digit: address + 1). "
         "Coils and discrete inputs are single bits. 32-bit values and floats take two registers, "
         "64-bit ones (u64, i64, f64) four, a string two characters a register (the first in "
         "the high byte); engineering value = register x scale. Access is the level a listener (or "
         "MQTT's "
         "`access`) must have to write the point: `operate` or `maintain`; `read` points are "
         "read-only.\n\n";
  if (listeners.empty()) {
    out << "Word order of 32-bit values and floats: big, high word first (mbpoll -B), unless a "
           "listener's `word_order` says otherwise; 64-bit values the same over four registers.\n";
  } else {
    out << "Word order of 32-bit values and floats (64-bit ones the same over four registers), "
           "per listener:\n\n";
    for (const auto& l : listeners) {
      out << "- " << md_field(l.listener) << ": " << word_order_text(l.word_order) << "\n";
    }
  }
  for (const auto& dev : devices) {
    out << "\n## Unit " << int{dev.device->unit_id} << ": " << dev.device->name << " ("
        << dev.device->adapter << ")\n\n"
        << "| table | address | reference | name | type | scale | unit | access | description | "
           "labels |\n"
        << "|---|---|---|---|---|---|---|---|---|---|\n";
    if (dev.forwards) {
      out << "| | | | pass-through: every request for this unit is forwarded to the slave as it "
             "is (docs/profiles.md, \"Pass-through\") | | | | | | |\n";
    }
    for (const MappedPoint* point : served(dev)) {
      const auto& p = *point;
      out << "| " << to_string(p.spec.table) << " | " << p.address << " | "
          << modicon_reference(p.spec.table, p.address, digits) << " | " << md_field(p.spec.name)
          << " | " << type_of(p) << " | " << number(p.spec.scale) << " | " << md_field(p.spec.unit)
          << " | " << access_of(p) << " | " << md_field(p.spec.description) << " | "
          << md_field(labels_text(p.spec)) << " |\n";
    }
  }
  return out.str();
}

}  // namespace

std::string format_regmap(const std::vector<DeviceRegisters>& devices,
                          const std::vector<ServedOn>& listeners, RegmapFormat format) {
  switch (format) {
    case RegmapFormat::json:
      return to_json(devices, listeners);
    case RegmapFormat::csv:
      return to_csv(devices);
    case RegmapFormat::markdown:
      return to_markdown(devices, listeners);
  }
  return {};
}

std::string modicon_reference(Table table, std::uint16_t address, int digits) {
  // The table's digit, then address + 1 filling the rest: 4 + 0006 + 1 -> "40007".
  long scale = 1;
  for (int i = 1; i < digits; ++i) scale *= 10;
  const long reference = table_rank(table) * scale + address + 1;
  std::string text = std::to_string(reference);
  return std::string(
             static_cast<std::size_t>(std::max<long>(0, digits - static_cast<long>(text.size()))),
             '0') +
         text;
}

}  // namespace drivegate
