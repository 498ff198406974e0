#include "expression.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>

namespace drivegate::framed {

// One step of the postfix program.
struct Expr::Node {
  enum class Op : std::uint8_t {
    number,  // push `num`
    text,    // push `str`
    var,     // push vars[slot]
    field,   // push fields[slot]
    sent,    // push sent[slot]
    neg,
    lnot,
    bnot,
    binary,   // pop b, pop a, push a `bin` b
    select,   // pop c, pop b, pop a: push a ? b : c
    call,     // pop `argc` arguments, push fn(...)
    index,    // pop i: push table[i] (0 outside it)
    length,   // push the table's length
    nearest,  // pop hi, lo, x: push the index in [lo, hi] whose entry is nearest x (ties: lower)
  };
  enum class Bin : std::uint8_t {
    add,
    sub,
    mul,
    div,
    mod,
    band,
    bor,
    bxor,
    shl,
    shr,
    eq,
    ne,
    lt,
    le,
    gt,
    ge,
    land,
    lor
  };
  enum class Fn : std::uint8_t { min, max, abs, round, floor, ceil, clamp, is_run, bit };

  Op op = Op::number;
  Bin bin = Bin::add;
  Fn fn = Fn::min;
  std::uint8_t argc = 0;
  double num = 0.0;
  const std::string* str = nullptr;
  std::size_t slot = 0;
  const std::vector<double>* table = nullptr;
};

namespace {

using Node = Expr::Node;
using Op = Node::Op;
using Bin = Node::Bin;
using Fn = Node::Fn;

constexpr std::size_t kMaxStack = 32;  // deeper than any rule a description needs
constexpr std::size_t kMaxNodes = 512;

std::int64_t whole(double v) {
  if (!std::isfinite(v)) return 0;
  if (v >= 9.2e18) return std::numeric_limits<std::int64_t>::max();
  if (v <= -9.2e18) return std::numeric_limits<std::int64_t>::min();
  return static_cast<std::int64_t>(v);
}

bool equal(const Val& a, const Val& b) {
  if (a.is_text() || b.is_text()) return a.is_text() && b.is_text() && *a.str == *b.str;
  return a.num == b.num;
}

double binary(Bin op, const Val& a, const Val& b) {
  const double x = a.num;
  const double y = b.num;
  switch (op) {
    case Bin::add:
      return x + y;
    case Bin::sub:
      return x - y;
    case Bin::mul:
      return x * y;
    case Bin::div:
      return y == 0.0 ? 0.0 : x / y;  // a rule never divides by zero on purpose
    case Bin::mod: {
      const std::int64_t d = whole(y);
      // By 0: 0, as division. By -1: 0 too, and never the overflow of the smallest number's.
      return d == 0 || d == -1 ? 0.0 : static_cast<double>(whole(x) % d);
    }
    case Bin::band:
      return static_cast<double>(whole(x) & whole(y));
    case Bin::bor:
      return static_cast<double>(whole(x) | whole(y));
    case Bin::bxor:
      return static_cast<double>(whole(x) ^ whole(y));
    case Bin::shl: {
      const std::int64_t n = whole(y);
      return n < 0 || n > 62 ? 0.0 : static_cast<double>(whole(x) << n);
    }
    case Bin::shr: {
      const std::int64_t n = whole(y);
      return n < 0 || n > 62 ? 0.0 : static_cast<double>(whole(x) >> n);
    }
    case Bin::eq:
      return equal(a, b) ? 1.0 : 0.0;
    case Bin::ne:
      return equal(a, b) ? 0.0 : 1.0;
    case Bin::lt:
      return x < y ? 1.0 : 0.0;
    case Bin::le:
      return x <= y ? 1.0 : 0.0;
    case Bin::gt:
      return x > y ? 1.0 : 0.0;
    case Bin::ge:
      return x >= y ? 1.0 : 0.0;
    case Bin::land:
      return a.truthy() && b.truthy() ? 1.0 : 0.0;
    case Bin::lor:
      return a.truthy() || b.truthy() ? 1.0 : 0.0;
  }
  return 0.0;
}

double round_half_away(double v) {
  return std::round(v);  // std::round rounds halves away from zero
}

struct FnInfo {
  std::string_view name;
  Fn fn;
  std::uint8_t min_args;
  std::uint8_t max_args;
};
constexpr std::array<FnInfo, 9> kFunctions = {{
    {"min", Fn::min, 2, 8},
    {"max", Fn::max, 2, 8},
    {"abs", Fn::abs, 1, 1},
    {"round", Fn::round, 1, 1},
    {"floor", Fn::floor, 1, 1},
    {"ceil", Fn::ceil, 1, 1},
    {"clamp", Fn::clamp, 3, 3},
    {"is_run", Fn::is_run, 1, 1},  // run_forward or run_reverse (include/drivegate/common.h)
    {"bit", Fn::bit, 2, 2},        // bit(x, n): bit n of x, 0 or 1
}};

double call(Fn fn, std::span<const Val> a) {
  switch (fn) {
    case Fn::min: {
      double v = a[0].num;
      for (const Val& x : a) v = std::min(v, x.num);
      return v;
    }
    case Fn::max: {
      double v = a[0].num;
      for (const Val& x : a) v = std::max(v, x.num);
      return v;
    }
    case Fn::abs:
      return std::fabs(a[0].num);
    case Fn::round:
      return round_half_away(a[0].num);
    case Fn::floor:
      return std::floor(a[0].num);
    case Fn::ceil:
      return std::ceil(a[0].num);
    case Fn::clamp:
      return std::clamp(a[0].num, a[1].num, std::max(a[1].num, a[2].num));
    case Fn::is_run:
      return a[0].num == 1.0 || a[0].num == 2.0 ? 1.0 : 0.0;
    case Fn::bit: {
      const std::int64_t n = whole(a[1].num);
      return n < 0 || n > 62 ? 0.0 : static_cast<double>((whole(a[0].num) >> n) & 1);
    }
  }
  return 0.0;
}

// The index in [lo, hi] of `t` whose entry is nearest `x`, the lower on a tie; -1 when the range
// holds no entry.
double nearest(const std::vector<double>& t, double x, double lo, double hi) {
  const std::int64_t from = std::max<std::int64_t>(0, whole(lo));
  const std::int64_t to =
      std::min<std::int64_t>(static_cast<std::int64_t>(t.size()) - 1, whole(hi));
  std::int64_t best = -1;
  for (std::int64_t i = from; i <= to; ++i) {
    if (best < 0 || std::fabs(t[static_cast<std::size_t>(i)] - x) <
                        std::fabs(t[static_cast<std::size_t>(best)] - x)) {
      best = i;
    }
  }
  return static_cast<double>(best);
}

// Recursive descent over the text, emitting the postfix program.
class Compiler {
 public:
  Compiler(std::string_view text, const Names& names) : s_(text), names_(names) {}

  bool run(std::vector<Node>& out, std::string& error) {
    skip();
    if (at_end()) return fail("empty expression", error);
    if (!ternary()) return fail(why_, error);
    skip();
    if (!at_end()) return fail("unexpected '" + std::string(s_.substr(pos_, 1)) + "'", error);
    if (nodes_.size() > kMaxNodes) return fail("too long", error);
    if (max_depth_ > static_cast<int>(kMaxStack)) return fail("too deeply nested", error);
    out = std::move(nodes_);
    return true;
  }

 private:
  bool fail(const std::string& what, std::string& error) {
    error = what + " at column " + std::to_string(std::min(pos_, s_.size()) + 1) + " of '" +
            std::string(s_) + "'";
    return false;
  }
  bool bad(std::string why) {
    if (why_.empty()) why_ = std::move(why);
    return false;
  }
  [[nodiscard]] bool at_end() const { return pos_ >= s_.size(); }
  void skip() {
    while (!at_end() && std::isspace(static_cast<unsigned char>(s_[pos_]))) ++pos_;
  }
  bool eat(std::string_view tok) {
    skip();
    if (s_.substr(pos_, tok.size()) != tok) return false;
    // "&" must not take the first half of "&&", "<" of "<<" or "<=", and so on.
    if (tok.size() == 1 && pos_ + 1 < s_.size()) {
      const char next = s_[pos_ + 1];
      const char c = tok[0];
      if ((c == '&' && next == '&') || (c == '|' && next == '|') ||
          ((c == '<' || c == '>') && (next == c || next == '=')) ||
          ((c == '=' || c == '!') && next == '=')) {
        return false;
      }
    }
    pos_ += tok.size();
    return true;
  }
  void emit(Node n) {
    switch (n.op) {
      case Op::number:
      case Op::text:
      case Op::var:
      case Op::field:
      case Op::sent:
      case Op::length:
        ++depth_;
        break;
      case Op::binary:
      case Op::index:
        --depth_;
        break;
      case Op::select:
      case Op::nearest:
        depth_ -= 2;
        break;
      case Op::call:
        depth_ -= n.argc - 1;
        break;
      default:
        break;
    }
    max_depth_ = std::max(max_depth_, depth_);
    nodes_.push_back(n);
  }
  void emit_bin(Bin b) {
    Node n;
    n.op = Op::binary;
    n.bin = b;
    emit(n);
  }

  bool ternary() {
    if (!binary_level(0)) return false;
    if (eat("?")) {
      if (!ternary()) return false;
      if (!eat(":")) return bad("expected ':'");
      if (!ternary()) return false;
      Node n;
      n.op = Op::select;
      emit(n);
    }
    return true;
  }

  // Binary operators by precedence, loosest first.
  struct Level {
    std::array<std::pair<std::string_view, Bin>, 4> ops;
    std::size_t count;
  };
  static constexpr std::array<Level, 10> kLevels = {{
      {{{{"||", Bin::lor}}}, 1},
      {{{{"&&", Bin::land}}}, 1},
      {{{{"|", Bin::bor}}}, 1},
      {{{{"^", Bin::bxor}}}, 1},
      {{{{"&", Bin::band}}}, 1},
      {{{{"==", Bin::eq}, {"!=", Bin::ne}}}, 2},
      {{{{"<=", Bin::le}, {">=", Bin::ge}, {"<", Bin::lt}, {">", Bin::gt}}}, 4},
      {{{{"<<", Bin::shl}, {">>", Bin::shr}}}, 2},
      {{{{"+", Bin::add}, {"-", Bin::sub}}}, 2},
      {{{{"*", Bin::mul}, {"/", Bin::div}, {"%", Bin::mod}}}, 3},
  }};

  bool binary_level(std::size_t level) {
    if (level == kLevels.size()) return unary();
    if (!binary_level(level + 1)) return false;
    for (;;) {
      const Level& l = kLevels[level];
      bool matched = false;
      for (std::size_t i = 0; i < l.count; ++i) {
        if (eat(l.ops[i].first)) {
          if (!binary_level(level + 1)) return false;
          emit_bin(l.ops[i].second);
          matched = true;
          break;
        }
      }
      if (!matched) return true;
    }
  }

  bool unary() {
    skip();
    if (++nesting_ > 64) return bad("too deeply nested");
    struct Exit {
      int& n;
      ~Exit() { --n; }
    } exit{nesting_};
    for (const auto& [tok, op] :
         {std::pair{"-", Op::neg}, std::pair{"!", Op::lnot}, std::pair{"~", Op::bnot}}) {
      if (eat(tok)) {
        if (!unary()) return false;
        Node n;
        n.op = op;
        emit(n);
        return true;
      }
    }
    if (eat("+")) return unary();
    return postfix();
  }

  bool postfix() {
    skip();
    if (at_end()) return bad("expression ends too early");
    const char c = s_[pos_];
    if (c == '(') {
      ++pos_;
      if (!ternary()) return false;
      if (!eat(")")) return bad("expected ')'");
      return true;
    }
    if (c == '\'') return text();
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') return number();
    if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') return name();
    return bad("unexpected '" + std::string(1, c) + "'");
  }

  bool text() {
    const std::size_t end = s_.find('\'', pos_ + 1);
    if (end == std::string_view::npos) return bad("unterminated text");
    Node n;
    n.op = Op::text;
    n.str = names_.text ? names_.text(s_.substr(pos_ + 1, end - pos_ - 1)) : nullptr;
    if (n.str == nullptr) return bad("no text here");
    pos_ = end + 1;
    emit(n);
    return true;
  }

  bool number() {
    std::size_t end = pos_;
    int base = 10;
    if (s_.substr(pos_, 2) == "0x" || s_.substr(pos_, 2) == "0X") base = 16;
    if (s_.substr(pos_, 2) == "0b" || s_.substr(pos_, 2) == "0B") base = 2;
    Node n;
    n.op = Op::number;
    if (base != 10) {
      end += 2;
      std::uint64_t v = 0;
      const auto [p, ec] = std::from_chars(s_.data() + end, s_.data() + s_.size(), v, base);
      if (ec != std::errc{} || p == s_.data() + end) return bad("bad number");
      pos_ = static_cast<std::size_t>(p - s_.data());
      n.num = static_cast<double>(v);
    } else {
      double v = 0;
      const auto [p, ec] = std::from_chars(s_.data() + end, s_.data() + s_.size(), v);
      if (ec != std::errc{} || !std::isfinite(v)) return bad("bad number");
      pos_ = static_cast<std::size_t>(p - s_.data());
      n.num = v;
    }
    if (!at_end() && (std::isalnum(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '_')) {
      return bad("bad number");
    }
    emit(n);
    return true;
  }

  bool name() {
    const std::size_t start = pos_;
    while (!at_end() && (std::isalnum(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '_' ||
                         s_[pos_] == '.')) {
      ++pos_;
    }
    const std::string_view id = s_.substr(start, pos_ - start);
    skip();
    if (!at_end() && s_[pos_] == '(') return function(id);
    if (!at_end() && s_[pos_] == '[') {
      const std::vector<double>* t = names_.table ? names_.table(id) : nullptr;
      if (t == nullptr) return bad("no table '" + std::string(id) + "'");
      ++pos_;
      if (!ternary()) return false;
      if (!eat("]")) return bad("expected ']'");
      Node n;
      n.op = Op::index;
      n.table = t;
      emit(n);
      return true;
    }
    const auto slot = names_.value ? names_.value(id) : std::nullopt;
    if (!slot) return bad("unknown name '" + std::string(id) + "'");
    Node n;
    n.op = slot->space == Space::var ? Op::var : slot->space == Space::field ? Op::field : Op::sent;
    n.slot = slot->index;
    emit(n);
    return true;
  }

  bool function(std::string_view id) {
    ++pos_;  // '('
    if (id == "len" || id == "nearest") {
      skip();
      const std::size_t start = pos_;
      while (!at_end() && (std::isalnum(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '_'))
        ++pos_;
      const std::string_view tname = s_.substr(start, pos_ - start);
      const std::vector<double>* t = names_.table ? names_.table(tname) : nullptr;
      if (t == nullptr) return bad(std::string(id) + "() takes a table first");
      Node n;
      n.table = t;
      if (id == "len") {
        if (!eat(")")) return bad("len() takes one table");
        n.op = Op::length;
        emit(n);
        return true;
      }
      // nearest(table, x, lo, hi)
      for (int i = 0; i < 3; ++i) {
        if (!eat(",")) return bad("nearest() takes a table, a value, a lowest and a highest index");
        if (!ternary()) return false;
      }
      if (!eat(")")) return bad("expected ')'");
      n.op = Op::nearest;
      emit(n);
      return true;
    }
    const auto f = std::find_if(kFunctions.begin(), kFunctions.end(),
                                [&](const FnInfo& i) { return i.name == id; });
    if (f == kFunctions.end()) return bad("unknown function '" + std::string(id) + "'");
    std::uint8_t argc = 0;
    if (!eat(")")) {
      do {
        if (!ternary()) return false;
        ++argc;
      } while (eat(","));
      if (!eat(")")) return bad("expected ')'");
    }
    if (argc < f->min_args || argc > f->max_args) {
      return bad(std::string(f->name) + "() takes " + std::to_string(f->min_args) +
                 (f->max_args != f->min_args ? ".." + std::to_string(f->max_args) : "") +
                 " arguments");
    }
    Node n;
    n.op = Op::call;
    n.fn = f->fn;
    n.argc = argc;
    emit(n);
    return true;
  }

  std::string_view s_;
  const Names& names_;
  std::size_t pos_ = 0;
  std::vector<Node> nodes_;
  std::string why_;
  int depth_ = 0;
  int max_depth_ = 0;
  int nesting_ = 0;
};

}  // namespace

Expr::Expr() = default;
Expr::~Expr() = default;
Expr::Expr(Expr&&) noexcept = default;
Expr& Expr::operator=(Expr&&) noexcept = default;
Expr::Expr(const Expr&) = default;
Expr& Expr::operator=(const Expr&) = default;

Expr Expr::number(double v) {
  Expr e;
  Node n;
  n.op = Op::number;
  n.num = v;
  e.nodes_.push_back(n);
  char buf[32];
  const auto [p, ec] = std::to_chars(buf, buf + sizeof buf, v);
  e.text_.assign(buf, ec == std::errc{} ? p : buf);
  return e;
}

std::optional<Expr> Expr::compile(std::string_view text, const Names& names, std::string& error) {
  Expr e;
  Compiler c(text, names);
  if (!c.run(e.nodes_, error)) return std::nullopt;
  e.text_ = std::string(text);
  return e;
}

Val Expr::eval(const Scope& scope) const {
  if (nodes_.empty()) return {};
  std::array<Val, kMaxStack> st;
  std::size_t sp = 0;
  for (const Node& n : nodes_) {
    switch (n.op) {
      case Op::number:
        st[sp++] = Val::of(n.num);
        break;
      case Op::text:
        st[sp++] = Val{0.0, n.str};
        break;
      case Op::var:
        st[sp++] = n.slot < scope.vars.size() ? scope.vars[n.slot] : Val{};
        break;
      case Op::field:
        st[sp++] = Val::of(n.slot < scope.fields.size() ? scope.fields[n.slot] : 0.0);
        break;
      case Op::sent:
        st[sp++] = Val::of(n.slot < scope.sent.size() ? scope.sent[n.slot] : 0.0);
        break;
      case Op::neg:
        st[sp - 1] = Val::of(-st[sp - 1].num);
        break;
      case Op::lnot:
        st[sp - 1] = Val::of(st[sp - 1].truthy() ? 0.0 : 1.0);
        break;
      case Op::bnot:
        st[sp - 1] = Val::of(static_cast<double>(~whole(st[sp - 1].num)));
        break;
      case Op::binary:
        st[sp - 2] = Val::of(binary(n.bin, st[sp - 2], st[sp - 1]));
        --sp;
        break;
      case Op::select:
        st[sp - 3] = st[sp - 3].truthy() ? st[sp - 2] : st[sp - 1];
        sp -= 2;
        break;
      case Op::call:
        st[sp - n.argc] = Val::of(call(n.fn, std::span<const Val>(&st[sp - n.argc], n.argc)));
        sp -= n.argc - 1;
        break;
      case Op::index: {
        const std::int64_t i = whole(st[sp - 1].num);
        const bool in = i >= 0 && i < static_cast<std::int64_t>(n.table->size());
        st[sp - 1] = Val::of(in ? (*n.table)[static_cast<std::size_t>(i)] : 0.0);
        break;
      }
      case Op::length:
        st[sp++] = Val::of(static_cast<double>(n.table->size()));
        break;
      case Op::nearest:
        st[sp - 3] = Val::of(nearest(*n.table, st[sp - 3].num, st[sp - 2].num, st[sp - 1].num));
        sp -= 2;
        break;
    }
  }
  return sp == 1 ? st[0] : Val{};
}

std::optional<double> Expr::constant() const {
  if (nodes_.size() == 1 && nodes_[0].op == Op::number) return nodes_[0].num;
  if (nodes_.size() == 2 && nodes_[0].op == Op::number && nodes_[1].op == Op::neg) {
    return -nodes_[0].num;
  }
  return std::nullopt;
}

bool Expr::reads(Space space) const {
  const Op want = space == Space::var ? Op::var : space == Space::field ? Op::field : Op::sent;
  return std::any_of(nodes_.begin(), nodes_.end(), [&](const Node& n) { return n.op == want; });
}

}  // namespace drivegate::framed
