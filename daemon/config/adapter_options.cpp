#include "adapter_options.h"

#include <map>
#include <sstream>
#include <vector>

namespace drivegate {
namespace {

std::vector<std::string> split_list(std::string_view s) {
  std::vector<std::string> out;
  std::string item;
  std::istringstream in{std::string(s)};
  while (std::getline(in, item, ',')) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

}  // namespace

bool in_choices(std::string_view choices, std::string_view value) {
  if (choices.empty()) return true;
  std::size_t start = 0;
  while (start <= choices.size()) {
    const auto bar = choices.find('|', start);
    const auto end = bar == std::string_view::npos ? choices.size() : bar;
    if (choices.substr(start, end - start) == value) return true;
    if (bar == std::string_view::npos) break;
    start = bar + 1;
  }
  return false;
}

std::string range_text(const OptionSpec& spec) {
  std::ostringstream out;
  out << spec.min << ".." << spec.max;
  return out.str();
}

std::optional<OptionValue> parse_option_text(const OptionSpec& spec, std::string_view text,
                                             std::string& error) {
  const std::string t(text);
  try {
    std::size_t used = 0;
    switch (spec.type) {
      case OptionType::integer: {
        const auto v = t.empty() ? 0 : std::stoll(t, &used, 0);
        if (!t.empty() && used != t.size()) break;
        if (spec.min != spec.max &&
            (static_cast<double>(v) < spec.min || static_cast<double>(v) > spec.max)) {
          error = std::string(spec.name) + ": must be in " + range_text(spec);
          return std::nullopt;
        }
        return OptionValue{v};
      }
      case OptionType::real: {
        const double v = t.empty() ? 0.0 : std::stod(t, &used);
        if (!t.empty() && used != t.size()) break;
        if (spec.min != spec.max && (v < spec.min || v > spec.max)) {
          error = std::string(spec.name) + ": must be in " + range_text(spec);
          return std::nullopt;
        }
        return OptionValue{v};
      }
      case OptionType::boolean:
        if (t == "true" || t == "false") return OptionValue{t == "true"};
        break;
      case OptionType::string:
        if (!in_choices(spec.choices, t)) {
          error = std::string(spec.name) + ": must be one of " + spec.choices;
          return std::nullopt;
        }
        return OptionValue{t};
      case OptionType::string_list:
        return OptionValue{split_list(t)};
    }
  } catch (const std::exception&) {
  }
  error = std::string(spec.name) + ": '" + t + "' is not a valid value";
  return std::nullopt;
}

Options default_options(const AdapterDescriptor& adapter) {
  std::map<std::string, OptionValue, std::less<>> values;
  for (std::size_t i = 0; i < adapter.option_count; ++i) {
    const OptionSpec& spec = adapter.options[i];
    std::string ignored;
    values[spec.name] =
        parse_option_text(spec, spec.default_value ? spec.default_value : "", ignored)
            .value_or(OptionValue{std::string()});
  }
  return Options(std::move(values));
}

}  // namespace drivegate
