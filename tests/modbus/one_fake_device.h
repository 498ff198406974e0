// A real gateway for the daemon's pieces to be tested against: one device, "d1", of the fake
// adapter (fake_adapter.h) at unit 1 on bus "a", whose port is never opened: the gateway judges a
// request before any line is involved. Built, not started.
#pragma once

#include <spdlog/sinks/null_sink.h>

#include <boost/asio/io_context.hpp>
#include <memory>
#include <string>
#include <vector>

#include "fake_adapter.h"
#include "gateway/gateway.h"
#include "plugin/adapter_options.h"

namespace drivegate::test {

class OneFakeDevice {
 public:
  // `history` (may be null) gets the gateway's audit records; it outlives this.
  explicit OneFakeDevice(History* history = nullptr) {
    plugins_.add(kFakeAdapter);
    Config config;
    config.path = "drivegate.toml";
    BusConfig bus;
    bus.name = "a";
    bus.port = "/nonexistent/tty-a";
    bus.baud = 4800;
    config.buses.push_back(bus);
    DeviceConfig device;
    device.name = "d1";
    device.bus = "a";
    device.adapter = "fake";
    device.unit_id = 1;
    device.address = 1;
    device.options = default_options(kFakeAdapter);
    config.devices.push_back(device);
    std::vector<std::string> errors;
    gateway_ = Gateway::build(io_, config, plugins_, log_, errors, false, history);
  }
  // Null if the build failed.
  [[nodiscard]] Gateway* gateway() const { return gateway_.get(); }
  boost::asio::io_context& io() { return io_; }
  [[nodiscard]] const std::shared_ptr<spdlog::logger>& log() const { return log_; }

 private:
  boost::asio::io_context io_;
  PluginRegistry plugins_;
  std::shared_ptr<spdlog::logger> log_ =
      std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::null_sink_mt>());
  std::unique_ptr<Gateway> gateway_;
};

}  // namespace drivegate::test
