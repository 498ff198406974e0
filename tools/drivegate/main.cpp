// drivegate: the command-line companion of drivegated. See drivegate(1).
#include <charconv>
#include <iostream>
#include <string>
#include <vector>

#include "commands.h"

namespace drivegate::cli {

std::optional<std::string> ArgReader::value(std::string_view flag) {
  if (done()) {
    std::cerr << "drivegate " << command_ << ": " << flag << " needs a value\n";
    return std::nullopt;
  }
  return std::string(next());
}

int ArgReader::usage(const std::string& what, const char* usage_text) const {
  std::cerr << "drivegate " << command_ << ": " << what << "\n" << usage_text;
  return 2;
}

int DeviceArgs::read(ArgReader& r, std::string_view flag, const char* usage_text) {
  auto v = r.value(flag);
  if (!v) return 2;
  if (flag == "--config") {
    config = *v;
  } else if (flag == "--device") {
    name = *v;
  } else if (flag == "--plugin-dir") {
    plugin_dir = *v;
  } else if (flag == "--timeout-ms") {
    unsigned long ms = 0;
    const auto [p, ec] = std::from_chars(v->data(), v->data() + v->size(), ms);
    if (ec != std::errc{} || p != v->data() + v->size() || ms < 1 || ms > 3'600'000) {
      return r.usage("--timeout-ms needs a number of milliseconds (1..3600000)", usage_text);
    }
    timeout = Millis(static_cast<long>(ms));
  } else {
    return r.usage("unknown argument '" + std::string(flag) + "'", usage_text);
  }
  return 0;
}

std::optional<Assignment> parse_assignment(std::string_view arg) {
  const auto eq = arg.find('=');
  if (eq == std::string_view::npos || eq == 0) return std::nullopt;
  return Assignment{std::string(arg.substr(0, eq)), std::string(arg.substr(eq + 1))};
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

constexpr const char* kUsage =
    "usage: drivegate COMMAND [ARGS]\n"
    "\n"
    "commands:\n"
    "  demo [--listen HOST:PORT]        simulators for every adapter and the daemon on them\n"
    "  sim ADAPTER [options]            one adapter's simulated device on a new pty\n"
    "  regmap --config FILE [--format json|csv|md]\n"
    "                                   print the Modbus register map\n"
    "  write --config FILE --device NAME POINT=VALUE...\n"
    "                                   write points directly, without the Modbus server\n"
    "  action --config FILE --device NAME [ACTION KEY=VALUE...]\n"
    "                                   a maintenance action of the device's adapter\n"
    "                                   (e.g. an FDC1's non-volatile programming)\n"
    "  capture --bus NAME [--seconds N] [-w FILE] [--http HOST:PORT]\n"
    "                                   a pcap of one bus from the running daemon\n"
    "                                   (tools/wireshark/ decodes it)\n"
    "  version\n"
    "\n"
    "Every command takes --plugin-dir DIR; `drivegate COMMAND --help` describes it.\n";

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << kUsage;
    return 2;
  }
  const std::string_view command = argv[1];
  std::vector<std::string_view> args(argv + 2, argv + argc);
  try {
    if (command == "regmap") return drivegate::cli::regmap(args);
    if (command == "sim") return drivegate::cli::sim(args);
    if (command == "demo") return drivegate::cli::demo(args);
    if (command == "write") return drivegate::cli::write(args);
    if (command == "action") return drivegate::cli::action(args);
    if (command == "capture") return drivegate::cli::capture(args);
    if (command == "version" || command == "--version") {
      std::cout << "drivegate " << DRIVEGATE_VERSION << "\n";
      return 0;
    }
    if (command == "help" || command == "--help" || command == "-h") {
      std::cout << kUsage;
      return 0;
    }
  } catch (const std::exception& e) {
    std::cerr << "drivegate " << command << ": " << e.what() << "\n";
    return 1;
  }
  std::cerr << "drivegate: unknown command '" << command << "'\n" << kUsage;
  return 2;
}
