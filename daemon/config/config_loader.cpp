#include "config_loader.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "base/read_file.h"
#include "drivegate/toml_reader.h"
#include "line_config.h"
#include "mqtt_config.h"
#include "plugin/adapter_options.h"
#include "port_address.h"
#include "server_config.h"

namespace drivegate {
namespace {

// A drivegate.toml of a few hundred drives is tens of KiB; anything past this is not one.
constexpr std::size_t kMaxConfigFile = 4 * 1024 * 1024;
constexpr std::size_t kMaxNameLength = 64;

// Names of buses and devices go into the journal (as fields), the status page, the JSON, metric
// labels and Sparkplug topics: letters, digits, '_', '-' and '.', starting with a letter or a
// digit, at most kMaxNameLength, so that none of them can inject a line, a tag or a topic level.
void check_name(const toml::node* at, const std::string& key, const std::string& name,
                Diagnostics& diag) {
  if (name.empty()) return;  // said elsewhere
  const auto safe = [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '-' || c == '.';
  };
  const bool alnum_first = safe(name[0]) && name[0] != '_' && name[0] != '-' && name[0] != '.';
  if (name.size() > kMaxNameLength || !alnum_first ||
      !std::all_of(name.begin(), name.end(), safe)) {
    diag.error(at, key,
               "names are 1 to " + std::to_string(kMaxNameLength) +
                   " letters, digits, '_', '-' or '.', starting with a letter or a digit");
  }
}

}  // namespace

namespace {

// One option from the TOML value, checked against its spec.
std::optional<OptionValue> read_option(const OptionSpec& spec, const toml::node& n,
                                       const std::string& key, Diagnostics& diag) {
  const bool bounded = spec.min != spec.max;
  switch (spec.type) {
    case OptionType::integer: {
      const auto* i = n.as_integer();
      if (i == nullptr) break;
      const auto v = i->get();
      if (bounded && (static_cast<double>(v) < spec.min || static_cast<double>(v) > spec.max)) {
        diag.error(&n, key, "must be in " + range_text(spec) + " (got " + std::to_string(v) + ")");
        return std::nullopt;
      }
      return OptionValue{v};
    }
    case OptionType::real: {
      double v = 0;
      if (const auto* i = n.as_integer()) {
        v = static_cast<double>(i->get());
      } else if (const auto* f = n.as_floating_point()) {
        v = f->get();
      } else {
        break;
      }
      if (!std::isfinite(v) || (bounded && (v < spec.min || v > spec.max))) {
        diag.error(&n, key, "must be a number in " + range_text(spec));
        return std::nullopt;
      }
      return OptionValue{v};
    }
    case OptionType::boolean:
      if (const auto* b = n.as_boolean()) return OptionValue{b->get()};
      break;
    case OptionType::string:
      if (const auto* s = n.as_string()) {
        if (!in_choices(spec.choices, s->get())) {
          diag.error(&n, key, std::string("must be one of ") + spec.choices);
          return std::nullopt;
        }
        return OptionValue{s->get()};
      }
      break;
    case OptionType::string_list:
      if (const auto* a = n.as_array()) {
        std::vector<std::string> items;
        for (const auto& item : *a) {
          const auto* s = item.as_string();
          if (s == nullptr) {
            diag.error(&item, key, "must be a list of strings");
            return std::nullopt;
          }
          items.push_back(s->get());
        }
        return OptionValue{std::move(items)};
      }
      break;
  }
  static constexpr std::array<const char*, 5> kTypeNames = {
      "an integer", "a number", "true or false", "a string", "a list of strings"};
  diag.error(&n, key, std::string("must be ") + kTypeNames.at(static_cast<std::size_t>(spec.type)));
  return std::nullopt;
}

// `lenient`: keys the schema does not know are left for a specialised schema to judge.
Options read_options(const AdapterDescriptor& adapter, const toml::table* table,
                     const std::string& prefix, Diagnostics& diag, bool lenient = false) {
  Options options = default_options(adapter);
  std::set<std::string> known;
  for (std::size_t i = 0; i < adapter.option_count; ++i) {
    const OptionSpec& spec = adapter.options[i];
    known.insert(spec.name);
    if (table == nullptr) continue;
    if (const toml::node* n = table->get(spec.name)) {
      if (auto v = read_option(spec, *n, prefix + "." + spec.name, diag)) {
        options.set(spec.name, std::move(*v));
      }
    }
  }
  if (table != nullptr && !lenient) {
    for (const auto& [key, node] : *table) {
      if (known.contains(std::string(key.str()))) continue;
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      diag.error(&node, prefix + "." + std::string(key.str()),
                 "unknown option for adapter '" + std::string(adapter.id) +
                     "' (known: " + (list.empty() ? "none" : list) + ")");
    }
  }
  return options;
}

std::vector<LineGiven> read_buses(const toml::table& root, Config& cfg, Diagnostics& diag) {
  std::vector<LineGiven> given;
  const auto* buses = array_of_tables(root, "bus", diag);
  if (buses == nullptr) return given;
  for (std::size_t i = 0; i < buses->size(); ++i) {
    const auto& t = *buses->get(i)->as_table();
    const std::string prefix = "bus[" + std::to_string(i) + "]";
    TableReader r(t, prefix, diag);
    r.expect({"name", "port", "baud", "parity", "data_bits", "stop_bits", "echo", "rs485",
              "reopen_max_ms", "network_delay_ms"});
    BusConfig bus;
    bus.line = line_of(t);
    bus.name = r.string("name", true).value_or("");
    check_name(r.node("name"), prefix + ".name", bus.name, diag);
    given.push_back(read_line(r, prefix, bus, diag));
    if (bus.name.empty() && t.get("name") != nullptr) diag.error(&t, prefix + ".name", "empty");
    for (const auto& other : cfg.buses) {
      if (!bus.name.empty() && other.name == bus.name) {
        diag.error(&t, prefix + ".name", "bus '" + bus.name + "' is declared twice");
      }
    }
    cfg.buses.push_back(std::move(bus));
  }
  return given;
}

std::optional<FailsafeAction> parse_failsafe_action(std::string_view s) {
  const auto it = std::find(kFailsafeActionNames.begin(), kFailsafeActionNames.end(), s);
  if (it == kFailsafeActionNames.end()) return std::nullopt;
  return static_cast<FailsafeAction>(it - kFailsafeActionNames.begin());
}

// failsafe_timeout_ms, failsafe_action, failsafe_rpm, on_shutdown and on_start (docs/safety.md).
void read_failsafe(TableReader& r, const std::string& prefix, DeviceConfig& dev,
                   Diagnostics& diag) {
  // 0 is off. Below 100 ms (the housekeeping period) a timeout could not be kept to anyway.
  if (auto v = r.integer("failsafe_timeout_ms", 0, 3'600'000, false)) {
    if (*v != 0 && *v < 100) {
      diag.error(r.node("failsafe_timeout_ms"), prefix + ".failsafe_timeout_ms",
                 "must be 0 (off) or 100..3600000");
    } else {
      dev.failsafe.timeout = Millis(*v);
    }
  }
  if (auto a = r.string("failsafe_action", false)) {
    if (auto action = parse_failsafe_action(*a)) {
      dev.failsafe.action = *action;
    } else {
      diag.error(r.node("failsafe_action"), prefix + ".failsafe_action",
                 "must be stop, quick_stop, hold or preset");
    }
  }
  const toml::node* rpm = r.node("failsafe_rpm");
  if (dev.failsafe.action == FailsafeAction::preset) {
    if (auto v = r.integer("failsafe_rpm", 0, 32767, true)) {
      dev.failsafe.preset_rpm = static_cast<std::int32_t>(*v);
    }
  } else if (rpm != nullptr) {
    diag.error(rpm, prefix + ".failsafe_rpm", "only used with failsafe_action = \"preset\"");
  }
  if (auto s = r.string("on_shutdown", false)) {
    if (*s == "stop") {
      dev.on_shutdown = ShutdownAction::stop;
    } else if (*s == "hold") {
      dev.on_shutdown = ShutdownAction::hold;
    } else {
      diag.error(r.node("on_shutdown"), prefix + ".on_shutdown", "must be stop or hold");
    }
  }
  if (auto s = r.string("on_start", false)) {
    if (*s == "adopt") {
      dev.on_start = StartAction::adopt;
    } else if (*s == "stop") {
      dev.on_start = StartAction::stop;
    } else {
      diag.error(r.node("on_start"), prefix + ".on_start", "must be adopt or stop");
    }
  }
}

void read_devices(const toml::table& root, Config& cfg, const PluginRegistry& plugins,
                  Diagnostics& diag) {
  const auto* devices = array_of_tables(root, "device", diag);
  if (devices == nullptr) return;
  for (std::size_t i = 0; i < devices->size(); ++i) {
    const auto& t = *devices->get(i)->as_table();
    const std::string prefix = "device[" + std::to_string(i) + "]";
    TableReader r(t, prefix, diag);
    r.expect({"name", "bus", "adapter", "unit_id", "address", "poll_ms", "budget_ms",
              "backoff_max_ms", "failsafe_timeout_ms", "failsafe_action", "failsafe_rpm",
              "on_shutdown", "on_start", "options"});
    DeviceConfig dev;
    dev.line = line_of(t);
    dev.name = r.string("name", true).value_or("");
    check_name(r.node("name"), prefix + ".name", dev.name, diag);
    dev.bus = r.string("bus", true).value_or("");
    dev.adapter = r.string("adapter", true).value_or("");
    dev.unit_id = static_cast<std::uint8_t>(r.integer("unit_id", 1, 247, true).value_or(0));
    if (auto v = r.integer("poll_ms", 10, 60'000, false)) dev.poll_interval = Millis(*v);
    if (auto v = r.integer("budget_ms", 10, 60'000, false)) dev.budget = Millis(*v);
    if (auto v = r.integer("backoff_max_ms", 100, 600'000, false)) dev.backoff_max = Millis(*v);
    read_failsafe(r, prefix, dev, diag);

    const AdapterDescriptor* adapter = nullptr;
    if (!dev.adapter.empty()) {
      adapter = plugins.find(dev.adapter);
      if (adapter == nullptr) {
        diag.error(r.node("adapter"), prefix + ".adapter",
                   "no adapter '" + dev.adapter + "' (installed: " + plugins.ids() + ")");
      }
    }
    const toml::node* address = r.node("address");
    const toml::node* options = r.node("options");
    if (adapter != nullptr && adapter->specialise != nullptr) {
      // A device that follows a description it names (the framed adapter): its options, line and
      // addresses are the description's, told by the descriptor specialised for it.
      const toml::table* opts = options != nullptr ? options->as_table() : nullptr;
      Diagnostics own(diag);  // the base schema's errors count once, below
      const Options base = read_options(*adapter, opts, prefix + ".options", own, true);
      std::string why;
      const AdapterDescriptor* device_adapter = specialised(*adapter, base, why);
      if (device_adapter == nullptr) {
        const toml::node* at = opts != nullptr && opts->get("protocol") != nullptr
                                   ? opts->get("protocol")
                                   : (options != nullptr ? options : &t);
        diag.error(at, prefix + ".options", why);
        dev.options = base;
      }
      adapter = device_adapter;
    }
    if (adapter != nullptr) {
      const bool addressed = adapter->address_max != 0;
      if (address == nullptr) {
        dev.address = adapter->default_address;
      } else if (!addressed) {
        diag.error(address, prefix + ".address",
                   "adapter '" + dev.adapter + "' has no bus address; remove the key");
      } else if (auto v = r.integer("address", adapter->address_min, adapter->address_max, false)) {
        dev.address = static_cast<std::uint32_t>(*v);
      }
      const toml::table* opts = options != nullptr ? options->as_table() : nullptr;
      if (options != nullptr && opts == nullptr) {
        diag.error(options, prefix + ".options", "must be a table ([device.options])");
      }
      dev.options = read_options(*adapter, opts, prefix + ".options", diag);
    }
    for (const auto& other : cfg.devices) {
      if (!dev.name.empty() && other.name == dev.name) {
        diag.error(&t, prefix + ".name", "device '" + dev.name + "' is declared twice");
      }
      if (dev.unit_id != 0 && other.unit_id == dev.unit_id) {
        diag.error(
            r.node("unit_id"), prefix + ".unit_id",
            "unit " + std::to_string(dev.unit_id) + " is already device '" + other.name + "'");
      }
      if (adapter != nullptr && adapter->address_max != 0 && other.bus == dev.bus &&
          other.address == dev.address) {
        diag.error(&t, prefix + ".address",
                   "address " + std::to_string(dev.address) + " is already device '" + other.name +
                       "' on bus '" + dev.bus + "'");
      }
    }
    cfg.devices.push_back(std::move(dev));
  }
}

// The adapters of a bus's devices, for the checks that they can share the line.
std::vector<const AdapterDescriptor*> adapters_on(const std::vector<const DeviceConfig*>& on_bus,
                                                  const PluginRegistry& plugins) {
  std::vector<const AdapterDescriptor*> out;
  for (const auto* dev : on_bus) {
    if (const AdapterDescriptor* a = plugins.find(dev->adapter, dev->options)) out.push_back(a);
  }
  return out;
}

bool same_framing(const LineDefaults& a, const LineDefaults& b) {
  return a.baud == b.baud && a.parity == b.parity && a.data_bits == b.data_bits &&
         a.stop_bits == b.stop_bits;
}

// Devices on one bus share its line settings. Those the [[bus]] leaves unset come from the
// adapters, so the adapters must agree on them: the framing, and echo, which decides whether the
// bus engine takes the first bytes it hears for its own. A device on the wrong side of either
// misreads every reply, so the user must choose rather than get the first device's setting.
void check_shared_line(const BusConfig& bus, const LineGiven& g,
                       const std::vector<const AdapterDescriptor*>& adapters, Diagnostics& diag) {
  const AdapterDescriptor* first = adapters.front();
  const std::string key = "bus '" + bus.name + "'";
  const auto framing = std::find_if(adapters.begin(), adapters.end(), [&](const auto* a) {
    return !same_framing(a->line, first->line);
  });
  if (!g.framing() && framing != adapters.end()) {
    diag.error_at(bus.line, key,
                  "its devices' adapters have different native line settings: set baud, "
                  "parity, data_bits and stop_bits explicitly");
  }
  const auto echo = std::find_if(adapters.begin(), adapters.end(),
                                 [&](const auto* a) { return a->line.echo != first->line.echo; });
  if (!g.echo && echo != adapters.end()) {
    const auto echo_of = [](const AdapterDescriptor* a) {
      return "'" + std::string(a->id) + "' echo = " + (a->line.echo ? "true" : "false");
    };
    diag.error_at(bus.line, key,
                  "its devices' adapters disagree on echo (" + echo_of(first) + ", " +
                      echo_of(*echo) + "): set echo explicitly");
  }
}

// Checks references between buses and devices and fills unset line settings from the adapters.
void cross_check(Config& cfg, const std::vector<LineGiven>& given, const PluginRegistry& plugins,
                 Diagnostics& diag) {
  for (const auto& dev : cfg.devices) {
    if (dev.bus.empty()) continue;
    const auto bus = std::find_if(cfg.buses.begin(), cfg.buses.end(),
                                  [&](const BusConfig& b) { return b.name == dev.bus; });
    if (bus == cfg.buses.end()) {
      diag.error_at(dev.line, "device '" + dev.name + "'.bus",
                    "no [[bus]] named '" + dev.bus + "'");
    }
  }
  for (std::size_t b = 0; b < cfg.buses.size(); ++b) {
    BusConfig& bus = cfg.buses[b];
    const LineGiven& g = given[b];
    std::vector<const DeviceConfig*> on_bus;
    for (const auto& dev : cfg.devices) {
      if (dev.bus == bus.name) on_bus.push_back(&dev);
    }
    if (on_bus.empty()) {
      diag.error_at(bus.line, "bus '" + bus.name + "'", "no device uses this bus");
      continue;
    }
    const AdapterDescriptor* first = plugins.find(on_bus.front()->adapter, on_bus.front()->options);
    if (first == nullptr) continue;
    for (const auto* dev : on_bus) {
      const AdapterDescriptor* a = plugins.find(dev->adapter, dev->options);
      if (a != nullptr && a->streaming && on_bus.size() > 1) {
        diag.error_at(dev->line, "device '" + dev->name + "'",
                      "adapter '" + dev->adapter +
                          "' streams unsolicited frames and must be alone on its bus");
      }
    }
    check_shared_line(bus, g, adapters_on(on_bus, plugins), diag);
    if (!g.baud) bus.baud = first->line.baud;
    if (!g.data_bits) bus.data_bits = first->line.data_bits;
    if (!g.stop_bits) bus.stop_bits = first->line.stop_bits;
    if (!g.parity) bus.parity = first->line.parity;
    if (!g.echo) bus.echo = first->line.echo;
  }
}

}  // namespace

ConfigResult parse_config(std::string_view text, const std::string& source_name,
                          const PluginRegistry& plugins) {
  ConfigResult result;
  Diagnostics diag(source_name);
  toml::table root;
  try {
    root = toml::parse(text, source_name);
  } catch (const toml::parse_error& e) {
    diag.error_at(static_cast<int>(e.source().begin.line), "", std::string(e.description()));
    result.errors = std::move(diag.errors);
    return result;
  }
  Config cfg;
  cfg.path = source_name;
  {
    TableReader top(root, "", diag);
    top.expect({"server", "listener", "http", "history", "mqtt", "bus", "device"});
    top.node("server");
    top.node("listener");
    top.node("http");
    top.node("history");
    top.node("mqtt");
    top.node("bus");
    top.node("device");
  }
  read_server(root, cfg, diag);
  read_listeners(root, cfg, diag);
  read_http(root, cfg, diag);
  read_history(root, cfg, diag);
  const auto given = read_buses(root, cfg, diag);
  check_serial_listeners(cfg, diag);
  read_devices(root, cfg, plugins, diag);
  read_mqtt(root, cfg, diag);
  if (cfg.devices.empty() && diag.errors.empty()) {
    diag.error_at(0, "device", "no [[device]] configured: there is nothing to serve");
  }
  cross_check(cfg, given, plugins, diag);
  if (diag.errors.empty()) {
    result.config = std::move(cfg);
    result.warnings = std::move(diag.warnings);
  } else {
    result.errors = std::move(diag.errors);
  }
  return result;
}

ConfigResult load_config(const std::filesystem::path& path, const PluginRegistry& plugins) {
  std::string error;
  const auto text = read_regular_file(path, kMaxConfigFile, error);
  if (!text) {
    ConfigResult r;
    r.errors.push_back(error);
    return r;
  }
  auto result = parse_config(*text, path.string(), plugins);
  if (result.config) result.config->path = path;
  return result;
}

}  // namespace drivegate
