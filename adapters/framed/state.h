// The variables of a described device at run time, as the driver and the simulator both keep them:
// the builtins, the options, the points and the states of the description, with the frame at hand
// and the request it answers laid out by field name for the expressions (description.h). Pure.
#pragma once

#include <deque>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "codec.h"
#include "description.h"
#include "drivegate/options.h"
#include "drivegate/point.h"

namespace drivegate::framed {

class State {
 public:
  // Every variable at its initial value: options from `options` (defaults for those missing),
  // states and points from their `initial`.
  State(const Description& d, const Options& options, std::uint32_t address);

  [[nodiscard]] const Description& description() const { return d_; }
  std::vector<Val>& vars() { return vars_; }
  [[nodiscard]] const std::vector<Val>& vars() const { return vars_; }
  [[nodiscard]] double num(std::size_t var) const { return vars_[var].num; }
  void set(std::size_t var, double v);
  // Whether a point's variable has a value yet (else the point reads "not known").
  [[nodiscard]] bool known(std::size_t var) const { return known_[var]; }

  // The scope of an expression over the variables alone, or with a frame and its request.
  [[nodiscard]] Scope scope() const { return {vars_, {}, {}}; }
  [[nodiscard]] Scope scope_with(std::span<const double> fields,
                                 std::span<const double> sent) const {
    return {vars_, fields, sent};
  }
  // A frame's fields laid out by global field id (the others 0), into `out`.
  void lay_out(const Message& m, std::span<const double> values, std::vector<double>& out) const;
  // The field values a message is sent with, from the variables (and the request it answers).
  void fill(const Message& m, std::span<const double> sent,
            std::array<double, kMaxFields>& out) const;
  // Runs assignments against the scope given: every right side first, then every target.
  void assign(const std::vector<Assign>& a, const Scope& scope);
  // Recomputes the derived points (Point::value).
  void derive();

  // A point's value as the register image takes it: an integer for a plain integer point, the
  // engineering value otherwise; not known until assigned.
  [[nodiscard]] Value point_value(std::size_t point) const;
  // The option texts' storage (a string option's value lives here).
  const std::string* intern(const std::string& s);

 private:
  const Description& d_;
  std::vector<Val> vars_;
  std::vector<bool> known_;
  std::deque<std::string> texts_;
  std::vector<double> scratch_;
};

}  // namespace drivegate::framed
