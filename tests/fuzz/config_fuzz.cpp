// Fuzz target: the configuration loader on arbitrary text, with every real adapter's descriptor
// (options validated against the real schemas) and the core's fake adapters. A configuration that
// loads is then built into a Gateway, so the adapters' factories meet every option combination
// the loader lets through.
#include <spdlog/sinks/null_sink.h>
#include <spdlog/spdlog.h>

#include <boost/asio/io_context.hpp>
#include <cstdint>
#include <string_view>

#include "check.h"
#include "config/config_loader.h"
#include "gateway/gateway.h"
#include "linked_adapters.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const drivegate::PluginRegistry plugins = drivegate::fuzz::linked_plugins();
  static const auto log =
      std::make_shared<spdlog::logger>("fuzz", std::make_shared<spdlog::sinks::null_sink_st>());
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto result = drivegate::parse_config(text, "fuzz.toml", plugins);
  // loader contract (config_loader.h): a configuration, or at least one error.
  FUZZ_CHECK(result.config.has_value() || !result.errors.empty());
  if (!result.config) return 0;
  boost::asio::io_context io;
  std::vector<std::string> errors;
  auto gateway = drivegate::Gateway::build(io, *result.config, plugins, log, errors);
  FUZZ_CHECK(gateway != nullptr || !errors.empty());
  return 0;
}
