#include "plugin/plugins.h"

#include <dlfcn.h>
#include <unistd.h>

#include <algorithm>
#include <stdexcept>
#include <system_error>

#include "plugin/adapter_options.h"

namespace drivegate {

// Owns one dlopen handle.
class PluginLibrary {
 public:
  explicit PluginLibrary(void* handle) : handle_(handle) {}
  ~PluginLibrary() {
    if (handle_ != nullptr) dlclose(handle_);
  }
  PluginLibrary(const PluginLibrary&) = delete;
  PluginLibrary& operator=(const PluginLibrary&) = delete;
  [[nodiscard]] void* handle() const { return handle_; }

 private:
  void* handle_;
};

PluginRegistry::PluginRegistry() = default;
PluginRegistry::~PluginRegistry() {
  descriptors_.clear();  // before the libraries they point into go away
  libraries_.clear();
}
PluginRegistry::PluginRegistry(PluginRegistry&&) noexcept = default;
PluginRegistry& PluginRegistry::operator=(PluginRegistry&&) noexcept = default;

std::vector<std::string> PluginRegistry::load_directory(const std::filesystem::path& dir) {
  std::vector<std::string> refused;
  std::error_code ec;
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.starts_with("drivegate-") && name.ends_with(".so")) files.push_back(entry.path());
  }
  if (ec) {
    refused.push_back("plugin directory " + dir.string() + ": " + ec.message());
    return refused;
  }
  std::sort(files.begin(), files.end());
  for (const auto& file : files) {
    if (std::string why = load_file(file); !why.empty()) refused.push_back(std::move(why));
  }
  return refused;
}

namespace {

// Why a descriptor cannot be used, or empty. Checked once here, so that the configuration loader,
// the tools and the drivers can rely on it: a complete descriptor of our API version whose option
// defaults parse against their own specs.
std::string descriptor_problem(const AdapterDescriptor& d) {
  if (d.api_version != kAdapterApiVersion) {
    return "adapter API version " + std::to_string(d.api_version) +
           ", this drivegate speaks version " + std::to_string(kAdapterApiVersion) +
           ": rebuild the plugin against this drivegate";
  }
  if (d.id == nullptr || d.create_driver == nullptr || d.create_simulator == nullptr ||
      (d.options == nullptr && d.option_count != 0)) {
    return "incomplete adapter descriptor";
  }
  if (std::string why = check_option_schema(d); !why.empty()) {
    return "adapter '" + std::string(d.id) + "': " + why;
  }
  return {};
}

}  // namespace

std::string PluginRegistry::load_file(const std::filesystem::path& file) {
  void* handle = dlopen(file.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) return file.string() + ": cannot load: " + dlerror();
  auto library = std::make_unique<PluginLibrary>(handle);
  const auto* d = static_cast<const AdapterDescriptor*>(dlsym(handle, kDescriptorSymbol));
  if (d == nullptr) {
    return file.string() + ": not a drivegate adapter (no symbol '" + kDescriptorSymbol + "')";
  }
  if (std::string why = descriptor_problem(*d); !why.empty()) return file.string() + ": " + why;
  if (find(d->id) != nullptr) {
    return file.string() + ": adapter '" + d->id + "' is already loaded from another file";
  }
  descriptors_.push_back(d);
  libraries_.push_back(std::move(library));
  return {};
}

void PluginRegistry::add(const AdapterDescriptor& descriptor) {
  // A descriptor linked into the program is the program's own bug: no caller has a user to tell.
  if (std::string why = descriptor_problem(descriptor); !why.empty()) {
    throw std::invalid_argument(why);
  }
  if (find(descriptor.id) != nullptr) {
    throw std::invalid_argument("adapter '" + std::string(descriptor.id) + "' is added twice");
  }
  descriptors_.push_back(&descriptor);
}

const AdapterDescriptor* PluginRegistry::find(std::string_view id) const {
  for (const auto* d : descriptors_) {
    if (id == d->id) return d;
  }
  return nullptr;
}

const AdapterDescriptor* PluginRegistry::find(std::string_view id, const Options& options) const {
  const AdapterDescriptor* base = find(id);
  if (base == nullptr) return nullptr;
  std::string error;
  return specialised(*base, options, error);
}

const AdapterDescriptor* specialised(const AdapterDescriptor& base, const Options& options,
                                     std::string& error) {
  if (base.specialise == nullptr) return &base;
  const AdapterDescriptor* d = base.specialise(options, error);
  if (d == nullptr) {
    if (error.empty()) error = "adapter '" + std::string(base.id) + "' cannot make this device";
    return nullptr;
  }
  if (std::string why = descriptor_problem(*d); !why.empty()) {
    error = why;
    return nullptr;
  }
  return d;
}

std::vector<const AdapterDescriptor*> PluginRegistry::all() const {
  return descriptors_;
}

std::string PluginRegistry::ids() const {
  std::string out;
  for (const auto* d : descriptors_) {
    if (!out.empty()) out += ", ";
    out += d->id;
  }
  return out.empty() ? "(none)" : out;
}

std::filesystem::path default_plugin_dir() {
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    // In the build tree the programs sit in <build>/bin and the plugins in <build>/adapters.
    auto build_dir = exe.parent_path().parent_path() / "adapters";
    if (std::filesystem::exists(build_dir / ".drivegate-build-tree", ec)) return build_dir;
  }
  return DRIVEGATE_PLUGIN_INSTALL_DIR;
}

}  // namespace drivegate
