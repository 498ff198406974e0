// drivegate write / fdc1-program: write points of one device directly on its serial line,
// without the Modbus server, with maintenance-only points (non-volatile programming) enabled.
#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <iostream>

#include "app/logging.h"
#include "commands.h"
#include "config/config_loader.h"
#include "gateway/gateway.h"
#include "gateway/value_codec.h"

namespace drivegate::cli {

namespace asio = boost::asio;

namespace {

constexpr const char* kUsage =
    "usage: drivegate write --config FILE --device NAME [--timeout-ms N] POINT=VALUE...\n"
    "\n"
    "Opens only that device's bus (stop the daemon first if it owns the port), waits for the\n"
    "device to come online, then writes each point in order and waits for the device to confirm\n"
    "it. VALUE is a number or one of the point's labels (e.g. command=run_forward).\n";

constexpr const char* kFdc1Usage =
    "usage: drivegate fdc1-program --config FILE --device NAME --KEY VALUE...\n"
    "\n"
    "Programs the FDC1's non-volatile settings: each --KEY VALUE writes point prog_KEY, then\n"
    "prog_commit validates every limit of the document and sends the 22-byte frame, confirmed\n"
    "by the controller's echo. `drivegate regmap` with maintenance points lists the keys.\n";

struct Assignment {
  std::string point;
  std::string value;
};

std::optional<double> parse_number(const std::string& s) {
  try {
    std::size_t used = 0;
    const double v = std::stod(s, &used);
    if (used == s.size()) return v;
  } catch (const std::exception&) {
  }
  return std::nullopt;
}

const char* exception_text(modbus::Exception e) {
  switch (e) {
    case modbus::Exception::none:
      return "ok";
    case modbus::Exception::illegal_data_address:
      return "not a writable point (0x02)";
    case modbus::Exception::illegal_data_value:
      return "value refused (0x03)";
    case modbus::Exception::server_device_failure:
      return "the device refused it (0x04)";
    case modbus::Exception::gateway_target_failed:
      return "the device did not confirm it in time (0x0B)";
    default:
      return "failed";
  }
}

// The adapter's own explanation of a failed write, when it publishes one: the string point
// named like the written one with its last word replaced by `message` (fdc1: prog_commit ->
// prog_message).
std::string failure_reason(Device& device, const std::string& point) {
  const auto cut = point.rfind('_');
  if (cut == std::string::npos) return {};
  const std::string name = point.substr(0, cut) + "_message";
  const auto& values = device.driver().values();
  for (const auto& p : device.map().points()) {
    if (p.common || p.spec.name != name || p.index >= values.size()) continue;
    if (const auto* s = std::get_if<std::string>(&values[p.index])) return *s;
  }
  return {};
}

int run_writes(const std::filesystem::path& config_path, const std::filesystem::path& plugin_dir,
               const std::string& device_name, const std::vector<Assignment>& writes,
               Millis timeout) {
  const PluginRegistry plugins = load_plugins(plugin_dir);
  auto result = load_config(config_path, plugins);
  for (const auto& e : result.errors) std::cerr << e << "\n";
  if (!result.config) return 1;
  Config cfg = *result.config;
  std::erase_if(cfg.devices, [&](const DeviceConfig& d) { return d.name != device_name; });
  if (cfg.devices.empty()) {
    std::cerr << "drivegate write: no device '" << device_name << "' in " << config_path << "\n";
    return 1;
  }
  std::erase_if(cfg.buses, [&](const BusConfig& b) { return b.name != cfg.devices[0].bus; });

  asio::io_context io;
  auto log = make_logger("write", spdlog::level::warn);
  std::vector<std::string> errors;
  auto gateway = Gateway::build(io, cfg, plugins, log, errors, /*maintenance=*/true);
  for (const auto& e : errors) std::cerr << e << "\n";
  if (!gateway) return 1;
  Device& device = *gateway->devices().front();

  // Resolve every assignment before anything is sent.
  struct Resolved {
    const MappedPoint* point;
    std::vector<std::uint16_t> registers;
  };
  std::vector<Resolved> resolved;
  for (const auto& w : writes) {
    const MappedPoint* point = nullptr;
    for (const auto& p : device.map().points()) {
      if (p.spec.name == w.point) point = &p;
    }
    if (point == nullptr || point->spec.access() != Access::read_write) {
      std::cerr << "drivegate write: " << device_name << " has no writable point '" << w.point
                << "'\n";
      return 1;
    }
    std::optional<double> v = parse_number(w.value);
    for (const auto& l : point->spec.labels) {
      if (l.name == w.value) v = l.value;
    }
    if (!v) {
      std::cerr << "drivegate write: " << w.point << ": '" << w.value << "' is not a number"
                << (point->spec.labels.empty() ? "" : " or a label of the point") << "\n";
      return 1;
    }
    std::vector<std::uint16_t> regs(point->spec.register_count(), 0);
    encode_value(point->spec, Value{*v}, regs);
    resolved.push_back({point, std::move(regs)});
  }

  int exit_code = 0;
  std::size_t next = 0;
  asio::steady_timer timer(io);
  const auto deadline = Clock::now() + timeout;
  std::function<void()> step = [&] {
    if (next == resolved.size()) {
      gateway->stop();
      return;
    }
    const Resolved& r = resolved[next];
    const auto done = [&](modbus::Exception e) {
      std::cout << writes[next].point << "=" << writes[next].value << ": " << exception_text(e);
      if (e != modbus::Exception::none) {
        if (const auto why = failure_reason(device, writes[next].point); !why.empty()) {
          std::cout << ": " << why;
        }
      }
      std::cout << std::endl;
      if (e != modbus::Exception::none) {
        exit_code = 1;
        gateway->stop();
        return;
      }
      ++next;
      asio::post(io, step);
    };
    const auto e =
        device.write(r.point->spec.table, r.point->address, r.registers, done, Clock::now());
    if (e != modbus::Exception::none) done(e);
  };
  std::function<void()> wait_online = [&] {
    if (device.online()) {
      step();
      return;
    }
    if (Clock::now() > deadline) {
      std::cerr << "drivegate write: " << device_name << " did not come online within "
                << timeout.count() << " ms\n";
      exit_code = 1;
      gateway->stop();
      return;
    }
    timer.expires_after(Millis(50));
    timer.async_wait([&](const boost::system::error_code& ec) {
      if (!ec) wait_online();
    });
  };
  gateway->start();
  wait_online();
  io.run();
  return exit_code;
}

}  // namespace

int write(std::span<const std::string_view> args) {
  ArgReader r("write", args);
  std::filesystem::path config, plugin_dir;
  std::string device;
  Millis timeout{10'000};
  std::vector<Assignment> writes;
  while (!r.done()) {
    const auto arg = r.next();
    if (arg == "--help") {
      std::cout << kUsage;
      return 0;
    }
    if (!arg.starts_with("--")) {
      const auto eq = arg.find('=');
      if (eq == std::string_view::npos || eq == 0) {
        return r.usage("'" + std::string(arg) + "' is not POINT=VALUE", kUsage);
      }
      writes.push_back({std::string(arg.substr(0, eq)), std::string(arg.substr(eq + 1))});
      continue;
    }
    auto v = r.value(arg);
    if (!v) return 2;
    if (arg == "--config") {
      config = *v;
    } else if (arg == "--device") {
      device = *v;
    } else if (arg == "--plugin-dir") {
      plugin_dir = *v;
    } else if (arg == "--timeout-ms") {
      const auto n = parse_number(*v);
      if (!n || *n < 1) return r.usage("--timeout-ms needs a positive number", kUsage);
      timeout = Millis(static_cast<long>(*n));
    } else {
      return r.usage("unknown argument '" + std::string(arg) + "'", kUsage);
    }
  }
  if (config.empty() || device.empty())
    return r.usage("--config and --device are required", kUsage);
  if (writes.empty()) return r.usage("nothing to write", kUsage);
  return run_writes(config, plugin_dir, device, writes, timeout);
}

int fdc1_program(std::span<const std::string_view> args) {
  ArgReader r("fdc1-program", args);
  std::vector<std::string> forwarded;
  std::vector<std::string> settings;
  while (!r.done()) {
    const auto arg = r.next();
    if (arg == "--help") {
      std::cout << kFdc1Usage;
      return 0;
    }
    if (!arg.starts_with("--")) return r.usage("unexpected '" + std::string(arg) + "'", kFdc1Usage);
    auto v = r.value(arg);
    if (!v) return 2;
    if (arg == "--config" || arg == "--device" || arg == "--plugin-dir" || arg == "--timeout-ms") {
      forwarded.emplace_back(arg);
      forwarded.push_back(*v);
    } else {
      std::string key(arg.substr(2));
      std::replace(key.begin(), key.end(), '-', '_');
      settings.push_back("prog_" + key + "=" + *v);
    }
  }
  if (settings.empty()) return r.usage("no settings given", kFdc1Usage);
  settings.emplace_back("prog_commit=1");
  forwarded.insert(forwarded.end(), settings.begin(), settings.end());
  std::vector<std::string_view> views(forwarded.begin(), forwarded.end());
  return write(views);
}

}  // namespace drivegate::cli
