#include "specialise.h"

#include <map>
#include <memory>
#include <mutex>
#include <vector>

#include "profile_options.h"
#include "settings.h"

namespace drivegate::modbus_device {
namespace {

// One specialised descriptor and everything its pointers point into.
struct Specialised {
  Profile profile;
  std::vector<std::string> defaults;
  std::vector<std::string> descriptions;
  std::vector<OptionSpec> options;
  AdapterDescriptor descriptor{};
};

}  // namespace

const AdapterDescriptor* specialise(const AdapterDescriptor& base, const Options& options,
                                    std::string& error) {
  static std::mutex mutex;
  // Kept for the process's lifetime: the core holds the pointer as long as the device lives, and
  // a reload may hand it out again. One per profile text (and where it was read from).
  static std::map<std::string, std::unique_ptr<Specialised>> made;
  const std::lock_guard lock(mutex);
  std::string key = "(plain)";
  std::optional<Profile> profile;
  if (!options.has("passthrough") || !options.boolean("passthrough")) {
    std::string why;
    const std::string name = options.has("profile") ? options.string("profile") : kDefaultProfile;
    if (auto text = find_profile(name, why)) {
      auto parsed = parse_profile(text->text, text->source);
      if (auto* p = std::get_if<Profile>(&parsed); p != nullptr && !p->options.empty()) {
        key = profile_read(*text);
        profile = std::move(*p);
      }
    }
  }
  if (const auto it = made.find(key); it != made.end()) return &it->second->descriptor;
  auto s = std::make_unique<Specialised>();
  s->options.assign(base.options, base.options + base.option_count);
  if (profile) {
    s->profile = std::move(*profile);
    for (const ProfileOption& o : s->profile.options) {
      s->defaults.push_back(number_text(o.required ? kUnsetOption : o.default_value));
      s->descriptions.push_back(o.description + (o.unit.empty() ? "" : " [" + o.unit + "]") +
                                " (profile " + s->profile.name + (o.required ? "; required" : "") +
                                ")");
    }
    for (std::size_t i = 0; i < s->profile.options.size(); ++i) {
      const ProfileOption& o = s->profile.options[i];
      OptionSpec spec{};
      spec.name = o.name.c_str();
      spec.type = OptionType::real;
      spec.default_value = s->defaults[i].c_str();
      spec.description = s->descriptions[i].c_str();
      // min < max: the profile's parser makes sure (min == max is unbounded). A required
      // option's schema is unbounded, so that its "not set" default is one; the device's value
      // is then held to min..max when the device is made (apply_options).
      spec.min = o.required ? 0.0 : o.min;
      spec.max = o.required ? 0.0 : o.max;
      s->options.push_back(spec);
    }
  }
  AdapterDescriptor& a = s->descriptor;
  a = base;
  a.options = s->options.data();
  a.option_count = s->options.size();
  a.specialise = nullptr;  // already one profile's
  (void)error;
  const AdapterDescriptor* out = &a;
  made.emplace(std::move(key), std::move(s));
  return out;
}

}  // namespace drivegate::modbus_device
