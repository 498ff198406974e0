// The `drivegate` subcommands. Each takes the arguments after its own name and returns the
// process exit code: 0 success, 1 failure, 2 usage error.
#pragma once

#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "config/plugins.h"
#include "point_writes.h"

namespace drivegate::cli {

int regmap(std::span<const std::string_view> args);
int sim(std::span<const std::string_view> args);
int demo(std::span<const std::string_view> args);
int write(std::span<const std::string_view> args);
int action(std::span<const std::string_view> args);
int capture(std::span<const std::string_view> args);

// Reads "--name VALUE" pairs and positionals, for the subcommands' small grammars.
class ArgReader {
 public:
  ArgReader(std::string_view command, std::span<const std::string_view> args)
      : command_(command), args_(args) {}
  [[nodiscard]] bool done() const { return pos_ >= args_.size(); }
  std::string_view next() { return args_[pos_++]; }
  // The value after a flag; prints a usage error and returns nullopt when it is missing.
  std::optional<std::string> value(std::string_view flag);
  int usage(const std::string& what, const char* usage_text) const;

 private:
  std::string_view command_;
  std::span<const std::string_view> args_;
  std::size_t pos_ = 0;
};

// The options `write` and `action` share: --config, --device, --plugin-dir, --timeout-ms.
struct DeviceArgs {
  std::filesystem::path config;
  std::filesystem::path plugin_dir;
  std::string name;
  Millis timeout{10'000};
  // Reads the value of `flag`, one of the above; a usage error (2) otherwise.
  int read(ArgReader& r, std::string_view flag, const char* usage_text);
};

// "POINT=VALUE" (or "KEY=VALUE"); nullopt when there is no '=' or nothing before it.
std::optional<Assignment> parse_assignment(std::string_view arg);

// Loads the plugins from --plugin-dir or the default place, reporting refusals on stderr.
PluginRegistry load_plugins(const std::filesystem::path& dir);

}  // namespace drivegate::cli
