#include "status_content.h"

#include <chrono>

#include "format/regmap_format.h"
#include "format/status_view.h"

namespace drivegate {

namespace {
double unix_now() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}
}  // namespace

StatusContent::StatusContent(const std::unique_ptr<Gateway>& gateway,
                             const modbus::Server& server)
    : gateway_(gateway), server_(server), started_unix_(unix_now()) {}

std::string StatusContent::status_json() {
  return drivegate::status_json({*gateway_, server_, DRIVEGATE_VERSION, started_unix_, unix_now()});
}

std::string StatusContent::metrics() {
  return metrics_text({*gateway_, server_, DRIVEGATE_VERSION, started_unix_, unix_now()});
}

std::string StatusContent::regmap_json() {
  std::vector<DeviceRegisters> devices;
  for (const auto& d : gateway_->devices()) devices.push_back({&d->config(), d->map()});
  return format_regmap(devices, RegmapFormat::json);
}

}  // namespace drivegate
