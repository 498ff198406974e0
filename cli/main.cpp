// drivegate: the command-line companion of drivegated. See drivegate(1).
#include <charconv>
#include <iostream>
#include <string>
#include <vector>

#include "commands.h"
#include "config/config_loader.h"

namespace drivegate::cli {

std::optional<ParsedArgs> parse_command(const CommandLine& cli, std::span<const std::string> args,
                                        int& exit_status) {
  ParsedArgs parsed = cli.parse(args);
  if (parsed.error) {
    exit_status = cli.usage_error(*parsed.error);
    return std::nullopt;
  }
  if (parsed.has("help")) {
    std::cout << cli.help();
    exit_status = 0;
    return std::nullopt;
  }
  return parsed;
}

std::optional<DeviceArgs> device_args(const CommandLine& cli, const ParsedArgs& parsed) {
  DeviceArgs out;
  out.config = parsed.value("config").value_or("");
  out.name = parsed.value("device").value_or("");
  out.plugin_dir = parsed.value("plugin-dir").value_or("");
  if (const auto v = parsed.value("timeout-ms")) {
    unsigned long ms = 0;
    const auto [p, ec] = std::from_chars(v->data(), v->data() + v->size(), ms);
    if (ec != std::errc{} || p != v->data() + v->size() || ms < 1 || ms > 3'600'000) {
      cli.usage_error("--timeout-ms needs a number of milliseconds (1..3600000), not '" + *v + "'");
      return std::nullopt;
    }
    out.timeout = Millis(static_cast<long>(ms));
  }
  if (out.config.empty() || out.name.empty()) {
    cli.usage_error("--config and --device are required");
    return std::nullopt;
  }
  return out;
}

std::optional<Assignment> parse_assignment(std::string_view arg) {
  const auto eq = arg.find('=');
  if (eq == std::string_view::npos || eq == 0) return std::nullopt;
  return Assignment{std::string(arg.substr(0, eq)), std::string(arg.substr(eq + 1))};
}

std::optional<DeviceCommand> device_command(const CommandLine& cli, const ParsedArgs& parsed,
                                            std::string_view form, int& exit_status) {
  auto device = device_args(cli, parsed);
  exit_status = 2;
  if (!device) return std::nullopt;
  std::vector<Assignment> writes;
  for (const auto& arg : parsed.operands) {
    auto a = parse_assignment(arg);
    if (!a) {
      cli.usage_error("'" + arg + "' is not " + std::string(form));
      return std::nullopt;
    }
    writes.push_back(std::move(*a));
  }
  if (writes.empty()) {
    cli.usage_error("nothing to write");
    return std::nullopt;
  }
  exit_status = 1;
  PluginRegistry plugins = load_plugins(device->plugin_dir);
  auto result = load_config(device->config, plugins);
  for (const auto& e : result.errors) std::cerr << e << "\n";
  if (!result.config) return std::nullopt;
  exit_status = 0;
  return DeviceCommand{std::move(*device), std::move(writes), std::move(plugins),
                       std::move(*result.config)};
}

PluginRegistry load_plugins(const std::filesystem::path& dir) {
  PluginRegistry plugins;
  for (const auto& refused : plugins.load_directory(dir.empty() ? default_plugin_dir() : dir)) {
    std::cerr << "drivegate: plugin " << refused << "\n";
  }
  return plugins;
}

}  // namespace drivegate::cli

namespace {

constexpr drivegate::Option kOptions[] = {
    {"version", 'V', nullptr, "print the version and exit"},
    drivegate::cli::kHelpOption,
};

// The commands are operands, not options: listed by hand, each with its own --help.
constexpr const char* kCommands =
    "commands:\n"
    "  demo       simulators for every adapter and the daemon on them\n"
    "  sim        one adapter's simulated device on a new pty (or a real port)\n"
    "  regmap     print the Modbus register map of a configuration\n"
    "  write      write points directly, without the Modbus server (daemon stopped)\n"
    "  action     a maintenance action of a device's adapter (e.g. an FDC1's\n"
    "             non-volatile programming)\n"
    "  capture    a pcap of one bus from the running daemon (for Wireshark)\n"
    "  events     the running daemon's history: commands, faults, trips, reloads\n"
    "  dcmd       a Sparkplug command (DCMD) to a device, through the broker of the\n"
    "             configuration, and its result\n"
#ifdef DRIVEGATE_SCAN
    "  scan       the Modbus slaves on a serial line, and the configuration for them\n"
    "  profile    check Modbus device profiles without a configuration\n"
#endif
#ifdef DRIVEGATE_PROTOCOL
    "  protocol   check a protocol description: decode and encode frames by hand\n"
#endif
    "  version    print the version\n"
    "\n"
    "`drivegate COMMAND --help` lists the command's options. See drivegate(1).";

drivegate::CommandLine command_line() {
  return drivegate::CommandLine("drivegate", kOptions, {"COMMAND [OPTION]... [ARG]...", "-V | -h"},
                                kCommands);
}

}  // namespace

int main(int argc, char** argv) {
  const auto cli = command_line();
  const std::vector<std::string> all(argv + 1, argv + argc);
  // Options before the command are drivegate's own; the command parses the rest.
  const auto parsed = cli.parse(all, drivegate::OperandOrder::options_first);
  if (parsed.error) return cli.usage_error(*parsed.error);
  if (parsed.has("help")) {
    std::cout << cli.help();
    return 0;
  }
  if (parsed.has("version")) {
    std::cout << "drivegate " << DRIVEGATE_VERSION << "\n";
    return 0;
  }
  if (parsed.operands.empty()) return cli.usage_error("which command?");
  const std::string& command = parsed.operands.front();
  const std::span<const std::string> args(parsed.operands.begin() + 1, parsed.operands.end());
  try {
    if (command == "regmap") return drivegate::cli::regmap(args);
    if (command == "sim") return drivegate::cli::sim(args);
    if (command == "demo") return drivegate::cli::demo(args);
    if (command == "write") return drivegate::cli::write(args);
    if (command == "action") return drivegate::cli::action(args);
    if (command == "capture") return drivegate::cli::capture(args);
    if (command == "events") return drivegate::cli::events(args);
    if (command == "dcmd") return drivegate::cli::dcmd(args);
#ifdef DRIVEGATE_SCAN
    if (command == "scan") return drivegate::cli::scan(args);
    if (command == "profile") return drivegate::cli::profile(args);
#endif
#ifdef DRIVEGATE_PROTOCOL
    if (command == "protocol") return drivegate::cli::protocol(args);
#endif
    if (command == "version") {
      std::cout << "drivegate " << DRIVEGATE_VERSION << "\n";
      return 0;
    }
    if (command == "help") {
      std::cout << cli.help();
      return 0;
    }
  } catch (const std::exception& e) {
    std::cerr << "drivegate " << command << ": " << e.what() << "\n";
    return 1;
  }
  return cli.usage_error("unknown command '" + command + "'");
}
