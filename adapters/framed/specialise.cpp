#include "specialise.h"

#include <array>
#include <list>
#include <map>
#include <mutex>
#include <vector>

#include "settings.h"

namespace drivegate::framed {
namespace {

// One specialised descriptor and everything its pointers point into.
struct Specialised {
  std::shared_ptr<const Description> description;
  std::string id;
  std::string summary;
  std::vector<OptionSpec> options;
  std::array<OptionSetting, 1> demo{};  // protocol = this description
  AdapterDescriptor descriptor{};
};

}  // namespace

std::string specialised_id(const AdapterDescriptor& base, const Description& d) {
  return std::string(base.id) + "/" + d.name;
}

const AdapterDescriptor* specialise(const AdapterDescriptor& base, const Options& options,
                                    std::string& error) {
  const std::string protocol = options.has("protocol") ? options.string("protocol") : "";
  auto d = load_description(protocol, error);
  if (!d) return nullptr;
  // Kept for the process's lifetime: the core holds the pointer as long as the device lives, and
  // a reload may hand it out again. One per description (load_description() caches them).
  static std::mutex mutex;
  static std::map<const Description*, std::unique_ptr<Specialised>> made;
  const std::lock_guard lock(mutex);
  if (const auto it = made.find(d.get()); it != made.end()) return &it->second->descriptor;
  auto s = std::make_unique<Specialised>();
  s->description = d;
  s->id = specialised_id(base, *d);
  s->summary = d->summary;
  s->options.assign(base.options, base.options + base.option_count);
  for (const Option& o : d->options) {
    OptionSpec spec{};
    spec.name = o.name.c_str();
    spec.type = o.type;
    spec.default_value = o.default_text.c_str();
    spec.description = o.description.c_str();
    spec.min = o.min;
    spec.max = o.max;
    spec.choices = o.choices.c_str();
    s->options.push_back(spec);
  }
  AdapterDescriptor& a = s->descriptor;
  a = base;
  a.id = s->id.c_str();
  a.summary = s->summary.c_str();
  a.options = s->options.data();
  a.option_count = s->options.size();
  a.line = d->line;
  a.address_min = d->address_min;
  a.address_max = d->address_max;
  a.default_address = d->address_default;
  a.streaming = d->streaming;
  s->demo[0] = {"protocol", d->name.c_str()};
  a.demo = {.options = s->demo.data(), .option_count = s->demo.size(), .running_rpm = d->demo_rpm};
  a.specialise = nullptr;  // already one device's
  const AdapterDescriptor* out = &a;
  made.emplace(d.get(), std::move(s));
  return out;
}

}  // namespace drivegate::framed
