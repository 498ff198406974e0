#include "regmap_format.h"

#include <cstdio>
#include <sstream>

#include "format/json.h"

namespace drivegate {
namespace {

const char* table_name(Table t) {
  switch (t) {
    case Table::coil:
      return "coil";
    case Table::discrete:
      return "discrete";
    case Table::input:
      return "input";
    case Table::holding:
      return "holding";
  }
  return "input";
}

const char* type_name(PointType t) {
  switch (t) {
    case PointType::u16:
      return "u16";
    case PointType::i16:
      return "i16";
    case PointType::u32:
      return "u32";
    case PointType::i32:
      return "i32";
    case PointType::f32:
      return "f32";
    case PointType::string:
      return "string";
  }
  return "u16";
}

std::string number(double v) {
  std::ostringstream out;
  out.precision(10);
  out << v;
  return out.str();
}

std::string type_of(const MappedPoint& p) {
  const bool bits = p.spec.table == Table::coil || p.spec.table == Table::discrete;
  return bits ? "u16" : type_name(p.spec.type);
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

std::string to_json(const std::vector<DeviceRegisters>& devices) {
  std::ostringstream out;
  out << "{\"devices\": [";
  for (std::size_t d = 0; d < devices.size(); ++d) {
    const auto& dev = devices[d];
    out << (d ? ",\n" : "\n") << "  {\"unit_id\": " << int{dev.device->unit_id}
        << ", \"name\": " << json_string(dev.device->name)
        << ", \"adapter\": " << json_string(dev.device->adapter) << ", \"points\": [";
    const auto& points = dev.map.points();
    for (std::size_t i = 0; i < points.size(); ++i) {
      const auto& p = points[i];
      out << (i ? ",\n" : "\n") << "    {\"name\": " << json_string(p.spec.name)
          << ", \"table\": \"" << table_name(p.spec.table) << "\", \"address\": " << p.address
          << ", \"type\": \"" << type_of(p) << "\", \"scale\": " << number(p.spec.scale)
          << ", \"unit\": " << json_string(p.spec.unit) << ", \"access\": \""
          << (p.spec.access() == Access::read_write ? "rw" : "r")
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
  out << "\n]}\n";
  return out.str();
}

std::string to_csv(const std::vector<DeviceRegisters>& devices) {
  std::ostringstream out;
  out << "unit_id,device,adapter,name,table,address,type,registers,scale,unit,access,description,"
         "labels\n";
  for (const auto& dev : devices) {
    for (const auto& p : dev.map.points()) {
      out << int{dev.device->unit_id} << "," << csv_field(dev.device->name) << ","
          << csv_field(dev.device->adapter) << "," << csv_field(p.spec.name) << ","
          << table_name(p.spec.table) << "," << p.address << "," << type_of(p) << ","
          << p.spec.register_count() << "," << number(p.spec.scale) << "," << csv_field(p.spec.unit)
          << "," << (p.spec.access() == Access::read_write ? "rw" : "r") << ","
          << csv_field(p.spec.description) << "," << csv_field(labels_text(p.spec)) << "\n";
    }
  }
  return out.str();
}

std::string to_markdown(const std::vector<DeviceRegisters>& devices) {
  std::ostringstream out;
  out << "# drivegate register map\n\n"
         "Addresses are 0-based (PLC reference = address + 1). 32-bit values and floats take two "
         "registers, high word first. Engineering value = register x scale.\n";
  for (const auto& dev : devices) {
    out << "\n## Unit " << int{dev.device->unit_id} << ": " << dev.device->name << " ("
        << dev.device->adapter << ")\n\n"
        << "| table | address | name | type | scale | unit | access | description | labels |\n"
        << "|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& p : dev.map.points()) {
      out << "| " << table_name(p.spec.table) << " | " << p.address << " | "
          << md_field(p.spec.name) << " | " << type_of(p) << " | " << number(p.spec.scale) << " | "
          << md_field(p.spec.unit) << " | " << (p.spec.access() == Access::read_write ? "rw" : "r")
          << " | " << md_field(p.spec.description) << " | " << md_field(labels_text(p.spec))
          << " |\n";
    }
  }
  return out.str();
}

}  // namespace

std::string format_regmap(const std::vector<DeviceRegisters>& devices, RegmapFormat format) {
  switch (format) {
    case RegmapFormat::json:
      return to_json(devices);
    case RegmapFormat::csv:
      return to_csv(devices);
    case RegmapFormat::markdown:
      return to_markdown(devices);
  }
  return {};
}

}  // namespace drivegate
