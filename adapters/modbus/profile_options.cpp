#include "profile_options.h"

#include <algorithm>
#include <charconv>
#include <cmath>

#include "settings.h"

namespace drivegate::modbus_device {
namespace {

bool is_name_char(char c) {
  return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
}

void read_option(const std::string& name, const toml::node& n, Diagnostics& diag,
                 Profile& profile) {
  const std::string key = "options." + name;
  const auto* t = n.as_table();
  if (t == nullptr) {
    diag.error(&n, key, "must be a table ([options." + name + "] with default, min, max, ...)");
    return;
  }
  std::string why;
  if (!valid_option_name(name, why)) {
    diag.error(&n, key, why);
    return;
  }
  TableReader r(*t, key, diag);
  r.expect({"default", "min", "max", "unit", "description"});
  // Values a drive's parameter takes; beyond a billion a factor would be meaningless anyway.
  constexpr double kLimit = 1e9;
  const auto def = r.number("default", -kLimit, kLimit, true);
  const auto min = r.number("min", -kLimit, kLimit, true);
  const auto max = r.number("max", -kLimit, kLimit, true);
  ProfileOption o;
  o.name = name;
  o.line = static_cast<std::uint32_t>(line_of(n));
  o.unit = r.string("unit", false).value_or("");
  const auto description = r.string("description", true);
  if (description && description->empty()) {
    diag.error(r.node("description"), key + ".description",
               "must say what the option is and where it is set on the drive");
  }
  o.description = description.value_or("");
  if (!def || !min || !max) return;
  if (*min >= *max) {
    // The daemon's option schema takes min == max for "unbounded"; a fixed value is a number.
    diag.error(r.node("min"), key + ".min",
               "must be below max (a value that cannot change is a number in rpm_factor)");
    return;
  }
  if (*def < *min || *def > *max) {
    diag.error(r.node("default"), key + ".default",
               "must be in min..max (" + number_text(*min) + ".." + number_text(*max) + ")");
    return;
  }
  o.value = o.default_value = *def;
  o.min = *min;
  o.max = *max;
  profile.options.push_back(std::move(o));
}

// Whether a term can be 0 within its option's range.
bool can_be_zero(const RpmFactor::Term& t, const std::vector<ProfileOption>& options) {
  if (!t.option) return t.number == 0.0;
  const ProfileOption& o = options[*t.option];
  return o.min <= 0.0 && o.max >= 0.0;
}

}  // namespace

std::string number_text(double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return {buf, r.ptr};
}

bool valid_option_name(std::string_view name, std::string& why) {
  if (name.empty() || name.size() > 32 || !(name[0] >= 'a' && name[0] <= 'z') ||
      !std::all_of(name.begin(), name.end(), is_name_char)) {
    why = "an option's name is snake_case: 1..32 characters, a-z first, then a-z, 0-9, '_'";
    return false;
  }
  for (const OptionSpec& spec : kOptionSchema) {
    if (name == spec.name) {
      why = "'" + std::string(name) + "' is an option of the modbus adapter itself";
      return false;
    }
  }
  return true;
}

bool read_profile_options(const toml::table& root, TableReader& top, Diagnostics& diag,
                          Profile& profile) {
  (void)root;
  const toml::node* n = top.node("options");
  if (n == nullptr) return true;
  const auto* t = n->as_table();
  if (t == nullptr) {
    diag.error(n, "options", "must be tables: [options.NAME]");
    return false;
  }
  const std::size_t errors = diag.errors.size();
  for (const auto& [k, v] : *t) read_option(std::string(k.str()), v, diag, profile);
  return diag.errors.size() == errors;
}

std::optional<RpmFactor> parse_rpm_factor(std::string_view text,
                                          const std::vector<ProfileOption>& options,
                                          std::string& why) {
  RpmFactor f;
  f.text = std::string(text);
  std::size_t i = 0;
  const auto skip = [&] {
    while (i < text.size() && text[i] == ' ') ++i;
  };
  bool divide = false;
  for (;;) {
    skip();
    if (i == text.size()) {
      why = f.terms.empty() ? "is empty: a number or an option name is needed"
                            : "ends in an operator: a number or an option name must follow it";
      return std::nullopt;
    }
    RpmFactor::Term t;
    t.divide = divide;
    const char c = text[i];
    if (c >= 'a' && c <= 'z') {
      const std::size_t start = i;
      while (i < text.size() && is_name_char(text[i])) ++i;
      const std::string name(text.substr(start, i - start));
      std::size_t index = 0;
      while (index < options.size() && options[index].name != name) ++index;
      if (index == options.size()) {
        std::string known;
        for (const auto& o : options) known += (known.empty() ? "" : ", ") + o.name;
        why = "names '" + name + "', which is not one of the profile's [options] (" +
              (known.empty() ? "it declares none" : "declared: " + known) + ")";
        return std::nullopt;
      }
      t.option = index;
    } else if ((c >= '0' && c <= '9') || c == '.') {
      const std::size_t start = i;
      while (i < text.size() && ((text[i] >= '0' && text[i] <= '9') || text[i] == '.')) ++i;
      const auto r = std::from_chars(text.data() + start, text.data() + i, t.number);
      if (r.ec != std::errc() || r.ptr != text.data() + i || !std::isfinite(t.number)) {
        why = "'" + std::string(text.substr(start, i - start)) + "' is not a number";
        return std::nullopt;
      }
    } else {
      why = std::string("'") + c +
            "' where a number or an option name belongs (a product and quotient of numbers and "
            "options: no + or -, no parentheses)";
      return std::nullopt;
    }
    if (can_be_zero(t, options)) {
      why = t.option ? "option " + options[*t.option].name + " can be 0 (its range is " +
                           number_text(options[*t.option].min) + ".." +
                           number_text(options[*t.option].max) + "): the factor" +
                           (t.divide ? " would divide by 0" : " would be 0")
                     : std::string(t.divide ? "divides by 0" : "is 0 with a factor of 0");
      return std::nullopt;
    }
    f.terms.push_back(t);
    skip();
    if (i == text.size()) return f;
    if (text[i] != '*' && text[i] != '/') {
      why = std::string("'") + text[i] +
            "' where '*' or '/' belongs (a product and quotient of numbers and options: no + or "
            "-, no parentheses)";
      return std::nullopt;
    }
    divide = text[i] == '/';
    ++i;
  }
}

double factor_value(const RpmFactor& factor, const std::vector<ProfileOption>& options) {
  double v = 1.0;
  for (const RpmFactor::Term& t : factor.terms) {
    const double x = t.option ? options[*t.option].value : t.number;
    v = t.divide ? v / x : v * x;
  }
  return v;
}

bool apply_options(Profile& profile, const Options& options, std::string& error) {
  for (ProfileOption& o : profile.options) {
    if (!options.has(o.name)) continue;
    const OptionValue& value = options.value(o.name);
    double v = 0;
    if (const auto* d = std::get_if<double>(&value)) {
      v = *d;
    } else if (const auto* i = std::get_if<std::int64_t>(&value)) {
      v = static_cast<double>(*i);
    } else {
      error = "option " + o.name + ": must be a number";
      return false;
    }
    if (!std::isfinite(v) || v < o.min || v > o.max) {
      error = "option " + o.name + ": must be a number in " + number_text(o.min) + ".." +
              number_text(o.max) + " (got " + number_text(v) + ")";
      return false;
    }
    o.value = v;
  }
  return true;
}

std::string options_text(const Profile& profile) {
  std::string out;
  for (const ProfileOption& o : profile.options) {
    if (!out.empty()) out += ", ";
    out += o.name + " = " + number_text(o.value);
    if (o.value == o.default_value) out += " (default)";
  }
  return out;
}

}  // namespace drivegate::modbus_device
