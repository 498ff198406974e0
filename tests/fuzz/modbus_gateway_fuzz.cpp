// Fuzz target: a Modbus TCP byte stream through the MBAP parser and the Dispatcher against the
// real Gateway behind the daemon's Modbus backend (modbus/backend_switch.h). The Gateway is built
// from a configuration with one device of every linked adapter (unit 1..n in registry order, each
// alone on its bus) plus the core's fake adapter, so Device::read / write validate every request
// and drivers receive every command, setpoint and point write a client can make. Buses are never
// opened: writes stay pending (their replies are not built).
//
// Input: one option byte (bits 3-7: segment size as in modbus_fake_fuzz.cpp), then the stream.
#include <spdlog/sinks/null_sink.h>
#include <spdlog/spdlog.h>

#include <boost/asio/io_context.hpp>
#include <cstdint>
#include <string>

#include "check.h"
#include "config/config_loader.h"
#include "fuzz_input.h"
#include "gateway/gateway.h"
#include "linked_adapters.h"
#include "modbus/backend_switch.h"
#include "modbus_stream.h"

namespace {

std::string gateway_config(const drivegate::PluginRegistry& plugins) {
  std::string text = "[server]\nlisten = \"127.0.0.1:1502\"\n";
  int unit = 0;
  for (const auto* a : plugins.all()) {
    if (std::string_view(a->id) == "streamer") continue;  // fake streamer: same driver as fake
    ++unit;
    const std::string n = std::to_string(unit);
    text += "[[bus]]\nname = \"bus" + n + "\"\nport = \"/dev/null\"\n";
    text += "[[device]]\nname = \"dev" + n + "\"\nbus = \"bus" + n + "\"\nadapter = \"" + a->id +
            "\"\nunit_id = " + n + "\n";
    // A device that follows a description names one: its adapter's demo does.
    if (a->specialise == nullptr || a->demo.option_count == 0) continue;
    text += "[device.options]\n";
    for (std::size_t i = 0; i < a->demo.option_count; ++i) {
      text += std::string(a->demo.options[i].name) + " = \"" + a->demo.options[i].value + "\"\n";
    }
  }
  return text;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const drivegate::PluginRegistry plugins = drivegate::fuzz::linked_plugins();
  static const auto config = [] {
    auto r = drivegate::parse_config(gateway_config(plugins), "fuzz.toml", plugins);
    FUZZ_CHECK(r.config.has_value());
    return *r.config;
  }();
  static const auto log =
      std::make_shared<spdlog::logger>("fuzz", std::make_shared<spdlog::sinks::null_sink_st>());

  drivegate::fuzz::FuzzInput in(data, size);
  const std::uint8_t options = in.u8();
  boost::asio::io_context io;
  std::vector<std::string> errors;
  auto gateway = drivegate::Gateway::build(io, config, plugins, log, errors);
  FUZZ_CHECK(gateway != nullptr);
  {
    drivegate::BackendSwitch backend;
    backend.set(gateway.get());
    drivegate::fuzz::ModbusStream stream(backend, [] { return false; });
    const std::size_t segment = options >> 3;
    while (!in.empty()) {
      const auto bytes = segment == 0 ? in.rest() : in.bytes(segment);
      if (!stream.receive(bytes)) break;
      io.poll();
      stream.complete_writes();
    }
  }
  io.poll();
  return 0;
}
