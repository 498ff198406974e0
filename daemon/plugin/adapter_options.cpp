#include "plugin/adapter_options.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <system_error>
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

// std::from_chars over the whole text. Unlike std::stoll / std::stod it takes no base prefix, no
// leading whitespace or '+', and (for doubles, in the default format) no hex floats, so a value
// reads the same here as in TOML.
template <class T>
std::errc parse_whole(std::string_view text, T& value) {
  const char* end = text.data() + text.size();
  const auto [stop, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc()) return ec;
  return stop == end ? std::errc() : std::errc::invalid_argument;
}

bool in_range(const OptionSpec& spec, double v) {
  return spec.min == spec.max || (v >= spec.min && v <= spec.max);
}

std::string quoted(const OptionSpec& spec, std::string_view text) {
  return std::string(spec.name) + ": '" + std::string(text) + "'";
}

std::optional<OptionValue> parse_integer(const OptionSpec& spec, std::string_view text,
                                         std::string& error) {
  std::int64_t v = 0;
  const std::errc ec = parse_whole(text, v);
  if (ec == std::errc::result_out_of_range) {
    error = quoted(spec, text) + " is out of the 64-bit integer range";
    return std::nullopt;
  }
  if (ec != std::errc()) {
    error = quoted(spec, text) + " is not a decimal integer";
    return std::nullopt;
  }
  if (!in_range(spec, static_cast<double>(v))) {
    error = std::string(spec.name) + ": must be in " + range_text(spec) + " (got " +
            std::string(text) + ")";
    return std::nullopt;
  }
  return OptionValue{v};
}

std::optional<OptionValue> parse_real(const OptionSpec& spec, std::string_view text,
                                      std::string& error) {
  double v = 0.0;
  // from_chars reads "inf" and "nan"; TOML has them too, and the TOML path refuses them as well.
  if (parse_whole(text, v) != std::errc() || !std::isfinite(v)) {
    error = quoted(spec, text) + " is not a finite decimal number";
    return std::nullopt;
  }
  if (!in_range(spec, v)) {
    error = std::string(spec.name) + ": must be in " + range_text(spec) + " (got " +
            std::string(text) + ")";
    return std::nullopt;
  }
  return OptionValue{v};
}

// The spec's default, parsed; nullopt and `why` ("default '12' is invalid: must be in 1..10 (got
// 12)") when the adapter's own default is unusable.
std::optional<OptionValue> parse_default(const OptionSpec& spec, std::string& why) {
  if (spec.default_value == nullptr) {
    why = "has no default";
    return std::nullopt;
  }
  std::string error;
  auto value = parse_option_text(spec, spec.default_value, error);
  if (!value) {
    // The option is named already; drop parse_option_text's "NAME: " lead.
    const std::string lead = std::string(spec.name) + ": ";
    if (error.starts_with(lead)) error.erase(0, lead.size());
    why = std::string("default '") + spec.default_value + "' is invalid: " + error;
  }
  return value;
}

// Why one spec is unusable, or empty; `seen` collects the names so far.
std::string check_spec(const OptionSpec& spec, std::size_t index,
                       std::set<std::string_view>& seen) {
  if (spec.name == nullptr || *spec.name == '\0') {
    return "option #" + std::to_string(index) + " has no name";
  }
  const std::string named = std::string("option '") + spec.name + "'";
  if (!seen.insert(spec.name).second) return named + " is declared twice";
  if (spec.description == nullptr) return named + " has no description";
  // in_choices() reads them; "" (the default) means free text.
  if (spec.type == OptionType::string && spec.choices == nullptr) return named + " has no choices";
  std::string why;
  if (!parse_default(spec, why)) return named + ": " + why;
  return {};
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
  out.precision(15);  // a double's exact digits: 6553500, not 6.5535e+06
  out << spec.min << ".." << spec.max;
  return out.str();
}

std::optional<OptionValue> parse_option_text(const OptionSpec& spec, std::string_view text,
                                             std::string& error) {
  switch (spec.type) {
    case OptionType::integer:
      return parse_integer(spec, text, error);
    case OptionType::real:
      return parse_real(spec, text, error);
    case OptionType::boolean:
      if (text == "true" || text == "false") return OptionValue{text == "true"};
      error = quoted(spec, text) + " is not true or false";
      return std::nullopt;
    case OptionType::string:
      if (!in_choices(spec.choices, text)) {
        error = std::string(spec.name) + ": must be one of " + spec.choices;
        return std::nullopt;
      }
      return OptionValue{std::string(text)};
    case OptionType::string_list:
      return OptionValue{split_list(text)};
  }
  error = std::string(spec.name) + ": unknown option type";
  return std::nullopt;
}

std::string check_option_schema(const AdapterDescriptor& adapter) {
  if (adapter.options == nullptr && adapter.option_count != 0) return "options missing";
  std::set<std::string_view> seen;
  for (std::size_t i = 0; i < adapter.option_count; ++i) {
    if (std::string why = check_spec(adapter.options[i], i, seen); !why.empty()) return why;
  }
  return {};
}

Options default_options(const AdapterDescriptor& adapter) {
  // Not a user's mistake: the plugin loader refuses such an adapter, so this is a program that
  // bypassed it. Better to stop than to hand a driver an option it never declared as default.
  if (std::string why = check_option_schema(adapter); !why.empty()) {
    throw std::logic_error(std::string("adapter '") + (adapter.id ? adapter.id : "?") +
                           "': " + why);
  }
  std::map<std::string, OptionValue, std::less<>> values;
  for (std::size_t i = 0; i < adapter.option_count; ++i) {
    const OptionSpec& spec = adapter.options[i];
    std::string ignored;
    values[spec.name] = *parse_option_text(spec, spec.default_value, ignored);
  }
  return Options(std::move(values));
}

bool set_option_text(const AdapterDescriptor& adapter, Options& options, std::string_view name,
                     std::string_view text, std::string& error) {
  for (std::size_t i = 0; i < adapter.option_count; ++i) {
    const OptionSpec& spec = adapter.options[i];
    if (name != spec.name) continue;
    auto value = parse_option_text(spec, text, error);
    if (!value) return false;
    options.set(spec.name, std::move(*value));
    return true;
  }
  error = std::string(name) + ": adapter '" + adapter.id + "' has no such option";
  return false;
}

namespace {

// A TOML basic string (TOML 1.0, "String"): quotes, backslashes and control characters escaped.
std::string toml_string(std::string_view s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7F) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04X",
                    static_cast<unsigned>(static_cast<unsigned char>(c)));
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

}  // namespace

std::string toml_literal(const OptionValue& value) {
  struct Visitor {
    std::string operator()(std::int64_t v) const { return std::to_string(v); }
    std::string operator()(double v) const {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.17g", v);
      std::string s = buf;
      // TOML needs a '.' or an exponent to read a float back as one.
      if (s.find_first_of(".eE") == std::string::npos) s += ".0";
      return s;
    }
    std::string operator()(bool v) const { return v ? "true" : "false"; }
    std::string operator()(const std::string& v) const { return toml_string(v); }
    std::string operator()(const std::vector<std::string>& v) const {
      std::string out = "[";
      for (std::size_t i = 0; i < v.size(); ++i) out += (i ? ", " : "") + toml_string(v[i]);
      return out + "]";
    }
  };
  return std::visit(Visitor{}, value);
}

}  // namespace drivegate
