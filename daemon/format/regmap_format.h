// The printed register map: JSON for tools, CSV for spreadsheets, Markdown for people.
#pragma once

#include <string>
#include <vector>

#include "config/config.h"
#include "gateway/register_map.h"

namespace drivegate {

struct DeviceRegisters {
  const DeviceConfig* device;
  RegisterMap map;
};

enum class RegmapFormat { json, csv, markdown };

std::string format_regmap(const std::vector<DeviceRegisters>& devices, RegmapFormat format);

}  // namespace drivegate
