// The printed register map: JSON for tools, CSV for spreadsheets, Markdown for people. Each
// device's points go table by table in the order of their Modicon references (coils 0xxxx,
// discrete inputs 1xxxx, input registers 3xxxx, holding registers 4xxxx), each table in address
// order, with the reference beside the 0-based address: PLC programmers think in references.
#pragma once

#include <string>
#include <vector>

#include "config/config.h"
#include "gateway/register_map.h"
#include "gateway/session.h"  // WordOrder

namespace drivegate {

struct DeviceRegisters {
  const DeviceConfig* device;
  RegisterMap map;
  // A pass-through device (Driver::forwards): every request for its unit goes to the slave as it
  // is, so none of `map` is served: it is printed as such, without points.
  bool forwards = false;
};

// A listener the map is served on, and the word order of the 32-bit values and floats there
// (its word_order: high word first, or low word first).
struct ServedOn {
  std::string listener;  // as the log names it: "0.0.0.0:502", "[::]:802 (TLS)"
  WordOrder word_order = WordOrder::big;
};

enum class RegmapFormat : std::uint8_t { json, csv, markdown };

// `listeners`: where the map is served (JSON and Markdown say each one's word order; empty:
// nothing said beyond the default, high word first).
std::string format_regmap(const std::vector<DeviceRegisters>& devices,
                          const std::vector<ServedOn>& listeners, RegmapFormat format);

// The Modicon reference of `address` in `table` ("30007" for input register 6), `digits` long:
// 5, or 6 where some address of the map is past 9998 and five digits cannot name it.
std::string modicon_reference(Table table, std::uint16_t address, int digits);

}  // namespace drivegate
