// The expressions of a protocol description (docs/protocols.md, "Expressions"): a field's value
// on the wire, a point's from a reply, a rule that confirms or refuses a write, a fault. Compiled
// once when the description is read, every name resolved then (an unknown one is an error naming
// it), and evaluated without allocating. Pure: no I/O, no clock.
//
//   speed * 10, error & 0x08, command == run_forward ? rpm[code] : 0, abs(rpm - setpoint) <= 100
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace drivegate::framed {

// A value: a number (integers are exact up to 2^53, which every field of 32 bits is), or a text
// (string options and literals, compared with == and != only).
struct Val {
  double num = 0.0;
  const std::string* str = nullptr;  // set for a text; owned by the description
  [[nodiscard]] bool is_text() const { return str != nullptr; }
  [[nodiscard]] bool truthy() const { return str != nullptr ? !str->empty() : num != 0.0; }
  static Val of(double n) { return {n, nullptr}; }
};

// Where a name's value lives when an expression runs: in the description's variables (options,
// points, state, the unified command and setpoint), a field of the frame at hand, or a field of the
// request that frame answers (`sent.NAME`).
enum class Space : std::uint8_t { var, field, sent };
struct Slot {
  Space space = Space::var;
  std::size_t index = 0;
};

// What a name may stand for while an expression is compiled: the resolver answers a slot, or
// nothing (then the expression does not compile and the error names it). A table is a list of
// numbers that `name[i]`, len(name) and nearest(name, x) read.
struct Names {
  std::function<std::optional<Slot>(std::string_view)> value;
  std::function<const std::vector<double>*(std::string_view)> table;
  std::function<const std::string*(std::string_view)> text;  // interns a literal's text
};

// The values an expression reads.
struct Scope {
  std::span<const Val> vars;
  std::span<const double> fields;
  std::span<const double> sent;
};

class Expr {
 public:
  Expr();
  ~Expr();
  Expr(Expr&&) noexcept;
  Expr& operator=(Expr&&) noexcept;
  Expr(const Expr&);
  Expr& operator=(const Expr&);

  // A constant.
  static Expr number(double v);
  // Compiles `text`; nullopt and `error` (naming what and where in the text) when it does not.
  static std::optional<Expr> compile(std::string_view text, const Names& names, std::string& error);

  [[nodiscard]] Val eval(const Scope& scope) const;
  [[nodiscard]] double num(const Scope& scope) const { return eval(scope).num; }
  [[nodiscard]] bool holds(const Scope& scope) const { return eval(scope).truthy(); }
  // The expression's value when it reads nothing (a constant), else nullopt.
  [[nodiscard]] std::optional<double> constant() const;
  [[nodiscard]] const std::string& text() const { return text_; }
  // Whether it reads this slot (a field, a variable): for load-time checks.
  [[nodiscard]] bool reads(Space space) const;

  struct Node;

 private:
  std::vector<Node> nodes_;  // postfix program, evaluated on a small stack
  std::string text_;
};

}  // namespace drivegate::framed
