// Loads adapter plugins: every drivegate-*.so in a directory, each found through its versioned,
// data-only descriptor. A plugin of another API version, or one without a descriptor, is refused
// with a message naming the file; the others still load.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "drivegate/adapter.h"

namespace drivegate {

class PluginLibrary;

class PluginRegistry {
 public:
  PluginRegistry();
  ~PluginRegistry();
  PluginRegistry(PluginRegistry&&) noexcept;
  PluginRegistry& operator=(PluginRegistry&&) noexcept;

  // Loads every plugin in `dir`. Returns one line per plugin refused (empty: all loaded).
  std::vector<std::string> load_directory(const std::filesystem::path& dir);
  // Loads one file; returns the reason on failure. Besides the API version and a complete
  // descriptor, every option must have a name of its own, a description and a default that its own
  // spec accepts: "FILE: adapter 'ID': option 'NAME': default '12' is invalid: must be in 1..10".
  std::string load_file(const std::filesystem::path& file);
  // Registers a descriptor linked into the program (tests), checked as load_file() checks a
  // plugin's; throws std::invalid_argument with the reason when it fails.
  void add(const AdapterDescriptor& descriptor);

  [[nodiscard]] const AdapterDescriptor* find(std::string_view id) const;
  // The descriptor a device of adapter `id` with these options runs under: the adapter's own, or
  // for one that specialises (AdapterDescriptor::specialise) the one of the description its options
  // name; nullptr when there is no such adapter or no such description.
  [[nodiscard]] const AdapterDescriptor* find(std::string_view id, const Options& options) const;
  [[nodiscard]] std::vector<const AdapterDescriptor*> all() const;
  [[nodiscard]] std::string ids() const;  // "a, b, c" for messages

 private:
  std::vector<std::unique_ptr<PluginLibrary>> libraries_;
  std::vector<const AdapterDescriptor*> descriptors_;
};

// `base` specialised for a device with `options` (AdapterDescriptor::specialise), checked as a
// plugin's descriptor is when it loads; `base` itself when it does not specialise. nullptr and
// `error` (one line) when it cannot be.
const AdapterDescriptor* specialised(const AdapterDescriptor& base, const Options& options,
                                     std::string& error);

// The plugin directory used when none is given: the build tree's when the program runs from it,
// the installed one otherwise.
std::filesystem::path default_plugin_dir();

}  // namespace drivegate
