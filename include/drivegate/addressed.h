// What a plugin's two factories both do first, for an adapter whose devices have a one-byte bus
// address: parse the options into the adapter's settings, then check the address, each refusing
// with its own one-line error. Header-only and compiled into each plugin (adapter.h's factories
// are what the daemon calls).
//
//   auto d = addressed(env.options, env.address, error, parse_settings, device_address);
//   if (!d) return nullptr;
//   return std::make_unique<MyDriver>(d->address, std::move(d->settings), env.poll_interval);
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>

#include "drivegate/options.h"

namespace drivegate {

template <class Settings>
struct Addressed {
  Settings settings;
  std::uint8_t address = 0;
};

// `parse(options, error)` gives std::optional<Settings>; `check(address, error)`, or
// `check(address, settings, error)` where the address depends on the settings, gives
// std::optional<std::uint8_t>. Nothing, with `error` set by the step that refused, unless both
// took their part.
template <class Parse, class Check>
auto addressed(const Options& options, std::uint32_t address, std::string& error, Parse parse,
               Check check) {
  using Settings = typename std::invoke_result_t<Parse, const Options&, std::string&>::value_type;
  std::optional<Addressed<Settings>> out;
  auto settings = parse(options, error);
  if (!settings) return out;
  std::optional<std::uint8_t> checked;
  if constexpr (std::is_invocable_v<Check, std::uint32_t, const Settings&, std::string&>) {
    checked = check(address, *settings, error);
  } else {
    checked = check(address, error);
  }
  if (checked) out = Addressed<Settings>{std::move(*settings), *checked};
  return out;
}

}  // namespace drivegate
