// Adapter options: the schema an adapter publishes for its `[device.options]` table, and the
// validated values the gateway hands to its factory. The gateway checks names, types and ranges
// against the schema (naming file and line on error) before an adapter sees anything.
#pragma once

#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>
#include <vector>

namespace drivegate {

enum class OptionType : std::uint8_t { integer, real, boolean, string, string_list };

struct OptionSpec {
  const char* name;
  OptionType type;
  // Default as text: "500", "4.0", "true", "normal"; string_list: comma-separated ("0D00,0D01"),
  // "" = empty. Every option has a default, so drivers never meet a missing one.
  const char* default_value;
  const char* description;
  double min = 0.0;  // integer / real only; min == max means unbounded
  double max = 0.0;
  const char* choices = "";  // string only: "normal|continuous"; empty = free text
};

using OptionValue = std::variant<std::int64_t, double, bool, std::string, std::vector<std::string>>;

// Validated options, defaults filled in. Getters assume the schema: asking for a name the schema
// does not declare, or with another type, is a programming error and throws std::logic_error.
class Options {
 public:
  Options() = default;
  explicit Options(std::map<std::string, OptionValue, std::less<>> values)
      : values_(std::move(values)) {}

  [[nodiscard]] std::int64_t integer(std::string_view name) const {
    return get<std::int64_t>(name);
  }
  [[nodiscard]] double real(std::string_view name) const { return get<double>(name); }
  [[nodiscard]] bool boolean(std::string_view name) const { return get<bool>(name); }
  [[nodiscard]] const std::string& string(std::string_view name) const {
    return get<std::string>(name);
  }
  [[nodiscard]] const std::vector<std::string>& string_list(std::string_view name) const {
    return get<std::vector<std::string>>(name);
  }
  [[nodiscard]] const OptionValue& value(std::string_view name) const {
    return get<OptionValue>(name);
  }
  [[nodiscard]] bool has(std::string_view name) const { return values_.contains(name); }
  // Every option by name, in name order.
  [[nodiscard]] const std::map<std::string, OptionValue, std::less<>>& all() const {
    return values_;
  }
  void set(std::string name, OptionValue value) { values_[std::move(name)] = std::move(value); }
  friend bool operator==(const Options&, const Options&) = default;

 private:
  template <class T>
  const T& get(std::string_view name) const {
    const auto it = values_.find(name);
    if (it == values_.end()) throw std::logic_error("option not in schema: " + std::string(name));
    if constexpr (std::is_same_v<T, OptionValue>) {
      return it->second;
    } else {
      const T* v = std::get_if<T>(&it->second);
      if (v == nullptr) throw std::logic_error("option has another type: " + std::string(name));
      return *v;
    }
  }
  std::map<std::string, OptionValue, std::less<>> values_;
};

}  // namespace drivegate
