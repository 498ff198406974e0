// drivegate: the command-line companion of drivegated. See drivegate(1).
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
    "  fdc1-program --config FILE --device NAME --KEY VALUE...\n"
    "                                   program an FDC1's non-volatile settings\n"
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
    if (command == "fdc1-program") return drivegate::cli::fdc1_program(args);
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
