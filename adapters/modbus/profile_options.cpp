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
  r.expect({"default", "example", "min", "max", "unit", "description"});
  // Values a drive's parameter takes; beyond a billion a factor would be meaningless anyway.
  constexpr double kLimit = 1e9;
  const toml::node* has_default = r.node("default");
  const toml::node* has_example = r.node("example");
  const char* const given = has_default != nullptr ? "default" : "example";
  const auto def = r.number(given, -kLimit, kLimit, false);
  if (has_default != nullptr && has_example != nullptr) {
    (void)r.number("example", -kLimit, kLimit, false);
    diag.error(has_example, key + ".example",
               "and default together: a default is the drive's factory value (cited), an "
               "example the value of an option every device must set; give one");
  } else if (has_default == nullptr && has_example == nullptr) {
    diag.error(&n, key,
               "needs a default (the drive's factory value, cited) or an example (then every "
               "device must set the option)");
  }
  const auto min = r.number("min", -kLimit, kLimit, true);
  const auto max = r.number("max", -kLimit, kLimit, true);
  ProfileOption o;
  o.name = name;
  o.line = static_cast<std::uint32_t>(line_of(n));
  o.required = has_default == nullptr;
  o.unit = r.string("unit", false).value_or("");
  const auto description = r.string("description", true);
  if (description && description->empty()) {
    diag.error(r.node("description"), key + ".description",
               "must say what the option is and where it is set on the drive");
  }
  o.description = description.value_or("");
  if (!def || !min || !max || (has_default != nullptr) == (has_example != nullptr)) return;
  if (*min >= *max) {
    // The daemon's option schema takes min == max for "unbounded"; a fixed value is a number.
    diag.error(r.node("min"), key + ".min",
               "must be below max (a value that cannot change is a number in rpm_factor)");
    return;
  }
  if (*def < *min || *def > *max) {
    diag.error(r.node(given), key + "." + given,
               "must be in min..max (" + number_text(*min) + ".." + number_text(*max) + ")");
    return;
  }
  o.value = o.default_value = *def;
  o.min = *min;
  o.max = *max;
  profile.options.push_back(std::move(o));
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

namespace {

// One operand at `i`: a number or the name of one of `options`; nullopt and `why` otherwise.
std::optional<RpmFactor::Operand> read_operand(std::string_view text, std::size_t& i,
                                               const std::vector<ProfileOption>& options,
                                               std::string& why) {
  RpmFactor::Operand o;
  const char c = i < text.size() ? text[i] : '\0';
  if (c >= 'a' && c <= 'z') {
    const std::size_t start = i;
    while (i < text.size() && is_name_char(text[i])) ++i;
    const std::string name(text.substr(start, i - start));
    std::size_t index = 0;
    while (index < options.size() && options[index].name != name) ++index;
    if (index == options.size()) {
      std::string known;
      for (const auto& opt : options) known += (known.empty() ? "" : ", ") + opt.name;
      why = "names '" + name + "', which is not one of the profile's [options] (" +
            (known.empty() ? "it declares none" : "declared: " + known) + ")";
      return std::nullopt;
    }
    o.option = index;
    return o;
  }
  if ((c >= '0' && c <= '9') || c == '.') {
    const std::size_t start = i;
    while (i < text.size() && ((text[i] >= '0' && text[i] <= '9') || text[i] == '.')) ++i;
    const auto r = std::from_chars(text.data() + start, text.data() + i, o.number);
    if (r.ec != std::errc() || r.ptr != text.data() + i || !std::isfinite(o.number)) {
      why = "'" + std::string(text.substr(start, i - start)) + "' is not a number";
      return std::nullopt;
    }
    return o;
  }
  return std::nullopt;  // the caller says what belongs there
}

const char* const kGrammar =
    "(a product and quotient of numbers, options and differences of two of them in parentheses: "
    "no +, no - outside them)";
const char* const kDifference =
    "a difference is two option names or numbers, '-' between them, in parentheses "
    "(\"(max_frequency_hz - min_frequency_hz)\")";

double operand_value(const RpmFactor::Operand& o, const std::vector<ProfileOption>& options) {
  return o.option ? options[*o.option].value : o.number;
}

double term_value(const RpmFactor::Term& t, const std::vector<ProfileOption>& options) {
  const double v = operand_value(t.operand, options);
  return t.minus ? v - operand_value(*t.minus, options) : v;
}

// Whether an operand can be 0 within its option's range.
bool can_be_zero(const RpmFactor::Operand& o, const std::vector<ProfileOption>& options) {
  if (!o.option) return o.number == 0.0;
  const ProfileOption& opt = options[*o.option];
  return opt.min <= 0.0 && opt.max >= 0.0;
}

// Whether a difference is 0 whatever the options: an option less itself, or two equal numbers.
bool always_zero(const RpmFactor::Term& t) {
  return t.minus && t.operand.option == t.minus->option &&
         (t.operand.option || t.operand.number == t.minus->number);
}

// The options `e` names, with their values: "max_frequency_hz = 10, min_frequency_hz = 50".
std::string named_options(const RpmFactor& e, const std::vector<ProfileOption>& options) {
  std::vector<std::size_t> named;
  for (const RpmFactor::Term& t : e.terms) {
    for (const auto* o : {&t.operand, t.minus ? &*t.minus : nullptr}) {
      if (o != nullptr && o->option &&
          std::find(named.begin(), named.end(), *o->option) == named.end()) {
        named.push_back(*o->option);
      }
    }
  }
  std::string out;
  for (const std::size_t i : named) {
    out += (out.empty() ? "" : ", ") + options[i].name + " = " + number_text(options[i].value);
  }
  return out;
}

// A factor's or an offset's text, parsed: what parse_rpm_factor and parse_rpm_offset share. A
// factor's terms must not be 0; an offset may be 0, but not divide by 0.
std::optional<RpmFactor> parse_expression(std::string_view text,
                                          const std::vector<ProfileOption>& options, RpmPart part,
                                          std::string& why) {
  why.clear();
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
    if (text[i] == '(') {
      // (a - b): the one parenthesised form.
      ++i;
      skip();
      auto a = read_operand(text, i, options, why);
      skip();
      if (a && i < text.size() && text[i] == '-') {
        ++i;
        skip();
        auto b = read_operand(text, i, options, why);
        skip();
        if (b && i < text.size() && text[i] == ')') {
          ++i;
          t.operand = *a;
          t.minus = *b;
        }
      }
      if (!t.minus) {
        if (why.empty()) {
          why = std::string("has parentheses around something other than a difference: ") +
                kDifference;
        }
        return std::nullopt;
      }
      if (always_zero(t)) {
        why = "has a difference that is always 0";
        return std::nullopt;
      }
    } else if (auto o = read_operand(text, i, options, why)) {
      t.operand = *o;
      const bool zero_matters = part == RpmPart::factor || t.divide;
      if (zero_matters && can_be_zero(t.operand, options)) {
        const ProfileOption* opt = t.operand.option ? &options[*t.operand.option] : nullptr;
        why = opt != nullptr ? "option " + opt->name + " can be 0 (its range is " +
                                   number_text(opt->min) + ".." + number_text(opt->max) +
                                   "): the " + (part == RpmPart::factor ? "factor" : "offset") +
                                   (t.divide ? " would divide by 0" : " would be 0")
                             : std::string(t.divide ? "divides by 0" : "is 0 with a factor of 0");
        return std::nullopt;
      }
    } else {
      if (why.empty()) {
        why = std::string("'") + text[i] + "' where a number or an option name belongs " + kGrammar;
      }
      return std::nullopt;
    }
    f.terms.push_back(t);
    skip();
    if (i == text.size()) break;
    if (text[i] != '*' && text[i] != '/') {
      why = std::string("'") + text[i] + "' where '*' or '/' belongs " + kGrammar;
      return std::nullopt;
    }
    divide = text[i] == '/';
    ++i;
  }
  // With the options' defaults and examples: what a device that sets none of them gets.
  if (std::string problem = rpm_problem(f, part, options); !problem.empty()) {
    why = problem + " (the options' defaults)";
    return std::nullopt;
  }
  return f;
}

}  // namespace

std::optional<RpmFactor> parse_rpm_factor(std::string_view text,
                                          const std::vector<ProfileOption>& options,
                                          std::string& why) {
  return parse_expression(text, options, RpmPart::factor, why);
}

std::optional<RpmFactor> parse_rpm_offset(std::string_view text,
                                          const std::vector<ProfileOption>& options,
                                          std::string& why) {
  return parse_expression(text, options, RpmPart::offset, why);
}

double factor_value(const RpmFactor& factor, const std::vector<ProfileOption>& options) {
  double v = 1.0;
  for (const RpmFactor::Term& t : factor.terms) {
    const double x = term_value(t, options);
    v = t.divide ? v / x : v * x;
  }
  return v;
}

std::string rpm_problem(const RpmFactor& e, RpmPart part,
                        const std::vector<ProfileOption>& options) {
  const double v = factor_value(e, options);
  const bool ok = part == RpmPart::factor ? std::isfinite(v) && v > 0.0 : std::isfinite(v);
  if (ok) return {};
  const std::string with = named_options(e, options);
  return "is " + (std::isfinite(v) ? number_text(v) : std::string("no number")) +
         (with.empty() ? "" : " with " + with) +
         (part == RpmPart::factor ? ": a factor must be above 0" : ": it must be a number");
}

RpmScale rpm_scale(const RpmFactor& factor, const std::optional<RpmFactor>& offset,
                   const std::vector<ProfileOption>& options) {
  return {factor_value(factor, options), offset ? factor_value(*offset, options) : 0.0};
}

bool check_rpm(const Profile& profile, std::string& error) {
  const CommonBindings& c = profile.common;
  const struct {
    const char* key;
    bool bound;
    const RpmFactor& factor;
    const std::optional<RpmFactor>& offset;
  } bindings[] = {
      {"speed_rpm", c.speed_rpm.has_value(), c.speed_factor, c.speed_offset},
      {"setpoint_rpm", c.setpoint_rpm.has_value(), c.setpoint_factor, c.setpoint_offset}};
  for (const auto& b : bindings) {
    if (!b.bound) continue;
    std::string problem = rpm_problem(b.factor, RpmPart::factor, profile.options);
    const char* what = "rpm_factor";
    if (problem.empty() && b.offset) {
      problem = rpm_problem(*b.offset, RpmPart::offset, profile.options);
      what = "rpm_offset";
    }
    if (!problem.empty()) {
      const std::string& text =
          what == std::string_view("rpm_factor") ? b.factor.text : b.offset->text;
      error = std::string("profile ") + profile.name + ": " + b.key + "'s " + what + " '" + text +
              "' " + problem + " (the device's options)";
      return false;
    }
  }
  return true;
}

bool apply_options(Profile& profile, const Options& options, std::string& error, Unset unset) {
  for (ProfileOption& o : profile.options) {
    const OptionValue* value = options.has(o.name) ? &options.value(o.name) : nullptr;
    const auto* d = value != nullptr ? std::get_if<double>(value) : nullptr;
    if (value == nullptr || (d != nullptr && *d == kUnsetOption)) {
      if (o.required && unset == Unset::refuse) {
        error = "option " + o.name + " is required and not set: " + o.description +
                (o.unit.empty() ? "" : " [" + o.unit + "]") + " (" + number_text(o.min) + ".." +
                number_text(o.max) + "; set it in [device.options])";
        return false;
      }
      continue;  // the default, or a required option's example
    }
    double v = 0;
    if (d != nullptr) {
      v = *d;
    } else if (const auto* i = std::get_if<std::int64_t>(value)) {
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
  return check_rpm(profile, error);
}

std::string options_text(const Profile& profile) {
  std::string out;
  for (const ProfileOption& o : profile.options) {
    if (!out.empty()) out += ", ";
    out += o.name + " = " + number_text(o.value);
    if (o.required) {
      out += " (required)";
    } else if (o.value == o.default_value) {
      out += " (default)";
    }
  }
  return out;
}

}  // namespace drivegate::modbus_device
