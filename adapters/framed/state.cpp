#include "state.h"

#include <cmath>
#include <variant>

namespace drivegate::framed {

State::State(const Description& d, const Options& options, std::uint32_t address)
    : d_(d), vars_(d.vars.size()), known_(d.vars.size(), false) {
  for (std::size_t i = 0; i < d_.vars.size(); ++i) {
    const Var& v = d_.vars[i];
    if (v.kind == Var::Kind::builtin || v.kind == Var::Kind::state) {
      vars_[i] = v.initial;
      known_[i] = true;
    }
  }
  vars_[builtin::address] = Val::of(address);
  for (const Option& o : d_.options) {
    Val v;
    if (options.has(o.name)) {
      const OptionValue& ov = options.value(o.name);
      if (const auto* i = std::get_if<std::int64_t>(&ov)) v = Val::of(static_cast<double>(*i));
      if (const auto* r = std::get_if<double>(&ov)) v = Val::of(*r);
      if (const auto* b = std::get_if<bool>(&ov)) v = Val::of(*b ? 1.0 : 0.0);
      if (const auto* s = std::get_if<std::string>(&ov)) v = Val{0.0, intern(*s)};
    } else if (o.type == OptionType::string) {
      v = Val{0.0, intern(o.default_text)};
    } else if (o.type == OptionType::boolean) {
      v = Val::of(o.default_text == "true" ? 1.0 : 0.0);
    } else {
      v = Val::of(std::strtod(o.default_text.c_str(), nullptr));
    }
    vars_[o.var] = v;
    known_[o.var] = true;
  }
  // States, then points, from the options (in declaration order).
  for (std::size_t i = 0; i < d_.vars.size(); ++i) {
    const Var& v = d_.vars[i];
    if (v.initial_expr) set(i, v.initial_expr->num(scope()));
  }
  derive();
}

void State::set(std::size_t var, double v) {
  vars_[var] = Val::of(v);
  known_[var] = true;
}

const std::string* State::intern(const std::string& s) {
  for (const std::string& t : texts_) {
    if (t == s) return &t;
  }
  texts_.push_back(s);
  return &texts_.back();
}

void State::lay_out(const Message& m, std::span<const double> values,
                    std::vector<double>& out) const {
  out.assign(d_.field_names.size(), 0.0);
  for (std::size_t i = 0; i < m.fields.size() && i < values.size(); ++i) {
    out[m.fields[i].global] = values[i];
  }
}

void State::fill(const Message& m, std::span<const double> sent,
                 std::array<double, kMaxFields>& out) const {
  const Scope s = scope_with({}, sent);
  for (std::size_t i = 0; i < m.fields.size(); ++i) out[i] = m.fields[i].value.num(s);
}

void State::assign(const std::vector<Assign>& a, const Scope& scope) {
  if (a.empty()) return;
  scratch_.resize(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) scratch_[i] = a[i].value.num(scope);
  for (std::size_t i = 0; i < a.size(); ++i) set(a[i].target, scratch_[i]);
}

void State::derive() {
  for (const Point& p : d_.points) {
    if (p.value) set(p.var, p.value->num(scope()));
  }
}

Value State::point_value(std::size_t point) const {
  const Point& p = d_.points[point];
  if (!known_[p.var]) return std::monostate{};
  const double v = vars_[p.var].num;
  if (!std::isfinite(v)) return std::monostate{};
  if (p.spec.type == PointType::string) return std::monostate{};
  const bool is_float = p.spec.type == PointType::f32 || p.spec.type == PointType::f64;
  if (p.spec.scale == 1.0 && !is_float) {
    return std::int64_t{static_cast<std::int64_t>(std::llround(v))};
  }
  return v;
}

}  // namespace drivegate::framed
