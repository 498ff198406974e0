#include "description_parser.h"

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <set>

#include "drivegate/toml_reader.h"

namespace drivegate::framed {

std::optional<std::size_t> Description::message(std::string_view wanted) const {
  return index_of(messages, wanted);
}

std::optional<std::size_t> Description::var(std::string_view wanted) const {
  return index_of(vars, wanted);
}

bool valid_protocol_name(std::string_view name) {
  return valid_file_name(name);
}

namespace {

// Names in a description (messages, fields, points, options, states, tables, checks): snake_case.
bool valid_name(std::string_view name) {
  if (name.empty() || name.size() > 48 || !(name[0] >= 'a' && name[0] <= 'z')) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
  });
}

template <std::size_t N>
std::optional<std::size_t> index_of(const std::array<std::string_view, N>& names,
                                    std::string_view s) {
  for (std::size_t i = 0; i < N; ++i) {
    if (names[i] == s) return i;
  }
  return std::nullopt;
}

std::optional<Fault> fault_named(std::string_view name) {
  if (const auto i = index_of(kFaultNames, name)) return static_cast<Fault>(*i);
  return std::nullopt;
}

constexpr std::array<std::string_view, 6> kCheckKindNames = {
    "xor", "sum", "sum_to", "twos_complement", "lrc", "crc"};
constexpr std::array<std::string_view, 5> kOptionTypeNames = {"integer", "real", "boolean",
                                                              "string", "string_list"};
constexpr std::array<std::string_view, 3> kAccessNames = {"maintain", "operate", "read"};
constexpr std::array<std::string_view, 3> kCountsNames = {"payload", "rest", "frame"};
constexpr std::array<std::string_view, 2> kDirectionNames = {"request", "reply"};

// The line an error names ("SOURCE:LINE: ..."), 0 when it names none.
unsigned long line_in(const std::string& error, const std::string& source) {
  if (error.compare(0, source.size() + 1, source + ":") != 0) return 0;
  return std::strtoul(error.c_str() + source.size() + 1, nullptr, 10);
}

int line_of_node(const toml::node* n) {
  return n != nullptr ? static_cast<int>(n->source().begin.line) : 0;
}

// Where an expression is read, and so what its names may stand for.
struct Context {
  const Message* own = nullptr;        // fields of this message
  std::vector<const Message*> frames;  // or: fields of any of these (the replies to a request)
  bool sent = false;                   // `sent.NAME`: a field of the request answered
};

class Parser {
 public:
  explicit Parser(const std::string& source) : diag_(source), source_(source) {}

  std::variant<std::shared_ptr<const Description>, std::vector<std::string>> run(
      std::string_view text) {
    toml::table root;
    try {
      root = toml::parse(text, source_);
    } catch (const toml::parse_error& e) {
      diag_.error_at(static_cast<int>(e.source().begin.line), "", std::string(e.description()));
      return std::move(diag_.errors);
    }
    d_ = std::make_shared<Description>();
    d_->source = source_;
    {
      TableReader top(root, "", diag_);
      top.expect({"protocol", "line", "timing", "framing", "check", "frame", "message", "option",
                  "state", "table", "point", "init", "poll", "command", "setpoint", "unified",
                  "fault", "simulator"});
      read_protocol(top);
      read_line(top);
      read_framing(top);
      read_checks(top);
      read_tables(top);
      add_builtins();
      read_options(top);
      read_states(top);
      read_points(top);
      read_messages(top);
      // Everything the expressions may name is known from here.
      read_timing(top);
      compile_messages(root);
      compile_points(root);
      read_periodic(top, "init", d_->init);
      read_periodic(top, "poll", d_->poll);
      read_commands(top);
      read_setpoint(top);
      read_unified(top);
      read_faults(top);
      read_simulator(top);
      check_safety(top);
    }
    if (!diag_.errors.empty()) {
      std::stable_sort(diag_.errors.begin(), diag_.errors.end(),
                       [&](const std::string& a, const std::string& b) {
                         return line_in(a, source_) < line_in(b, source_);
                       });
      return std::move(diag_.errors);
    }
    return std::shared_ptr<const Description>(std::move(d_));
  }

 private:
  // ---- helpers -----------------------------------------------------------------------------

  // A name's declaration: valid and not taken by another variable or table.
  bool declare(const toml::node* at, const std::string& key, const std::string& name) {
    if (!valid_name(name)) {
      diag_.error(at, key, "'" + name + "' is not a name: a-z first, then a-z, 0-9 and '_'");
      return false;
    }
    if (taken_.contains(name)) {
      diag_.error(at, key,
                  "'" + name +
                      "' is declared twice (options, states, points and "
                      "tables share one namespace)");
      return false;
    }
    taken_.insert(name);
    return true;
  }

  const std::string* intern(std::string_view s) {
    for (const std::string& t : d_->texts) {
      if (t == s) return &t;
    }
    d_->texts.emplace_back(s);
    return &d_->texts.back();
  }

  std::optional<std::size_t> var_of(std::string_view name) const { return d_->var(name); }

  std::optional<std::size_t> field_id(std::string_view name) const {
    const auto& f = d_->field_names;
    const auto it = std::find(f.begin(), f.end(), name);
    if (it == f.end()) return std::nullopt;
    return static_cast<std::size_t>(it - f.begin());
  }

  Names names_for(const Context& ctx) {
    Names n;
    n.value = [this, ctx](std::string_view id) -> std::optional<Slot> {
      if (id.starts_with("sent.")) {
        if (!ctx.sent) return std::nullopt;
        if (const auto f = field_id(id.substr(5))) return Slot{Space::sent, *f};
        return std::nullopt;
      }
      const auto has_field = [&](const Message* m) {
        return std::any_of(m->fields.begin(), m->fields.end(),
                           [&](const Field& f) { return f.name == id; });
      };
      if ((ctx.own != nullptr && has_field(ctx.own)) ||
          std::any_of(ctx.frames.begin(), ctx.frames.end(), has_field)) {
        return Slot{Space::field, *field_id(id)};
      }
      if (const auto v = var_of(id)) return Slot{Space::var, *v};
      return std::nullopt;
    };
    n.table = [this](std::string_view id) -> const std::vector<double>* {
      for (const Table& t : d_->tables) {
        if (t.name == id) return &t.values;
      }
      return nullptr;
    };
    n.text = [this](std::string_view s) { return intern(s); };
    return n;
  }

  // An expression from a TOML string, integer, float or boolean.
  std::optional<Expr> expr(const toml::node* n, const std::string& key, const Context& ctx = {}) {
    if (n == nullptr) return std::nullopt;
    if (const auto* i = n->as_integer()) return Expr::number(static_cast<double>(i->get()));
    if (const auto* f = n->as_floating_point()) return Expr::number(f->get());
    if (const auto* b = n->as_boolean()) return Expr::number(b->get() ? 1.0 : 0.0);
    const auto* s = n->as_string();
    if (s == nullptr) {
      diag_.error(n, key, "must be a number or an expression in a string");
      return std::nullopt;
    }
    std::string why;
    auto e = Expr::compile(s->get(), names_for(ctx), why);
    if (!e) diag_.error(n, key, why);
    return e;
  }
  std::optional<Expr> expr(TableReader& r, std::string_view key, const Context& ctx = {}) {
    return expr(r.node(key), r.qualified(key), ctx);
  }

  std::optional<std::size_t> message_ref(TableReader& r, std::string_view key,
                                         std::optional<Direction> dir, bool required) {
    const auto name = r.string(key, required);
    if (!name) return std::nullopt;
    const auto m = d_->message(*name);
    if (!m) {
      diag_.error(r.node(key), r.qualified(key), "no message '" + *name + "'");
      return std::nullopt;
    }
    if (dir && d_->messages[*m].direction != *dir) {
      diag_.error(
          r.node(key), r.qualified(key),
          "message '" + *name + "' is a " +
              std::string(kDirectionNames[static_cast<std::size_t>(d_->messages[*m].direction)]) +
              ", not a " + std::string(kDirectionNames[static_cast<std::size_t>(*dir)]));
      return std::nullopt;
    }
    return m;
  }

  std::optional<std::size_t> var_ref(const toml::node* at, const std::string& key,
                                     std::string_view name, bool writable) {
    const auto v = var_of(name);
    if (!v || d_->vars[*v].kind == Var::Kind::option ||
        (writable && d_->vars[*v].kind == Var::Kind::builtin)) {
      diag_.error(at, key,
                  "'" + std::string(name) + "' is not a point or a state" +
                      (writable ? " (only those can be assigned)" : ""));
      return std::nullopt;
    }
    return v;
  }

  // `{ target = "expr", ... }`: assignments to points and states.
  std::vector<Assign> assignments(const toml::node* n, const std::string& key, const Context& ctx) {
    std::vector<Assign> out;
    if (n == nullptr) return out;
    const auto* t = n->as_table();
    if (t == nullptr) {
      diag_.error(n, key, "must be a table of assignments such as { speed = \"rpm * 10\" }");
      return out;
    }
    for (const auto& [k, v] : *t) {
      const std::string name(k.str());
      const std::string where = key + "." + name;
      const auto target = var_ref(&v, where, name, true);
      auto e = expr(&v, where, ctx);
      if (target && e) out.push_back({*target, std::move(*e)});
    }
    return out;
  }

  // ---- [protocol], [line], [framing], [timing] ---------------------------------------------

  void read_protocol(TableReader& top) {
    top.read_table("protocol", true, [&](TableReader& r) {
      r.expect({"name", "summary", "document", "demo_rpm"});
      if (auto name = r.file_name("name")) d_->name = *name;
      d_->summary = r.string("summary", true).value_or("");
      // Where every byte comes from: a description without it cannot be checked against anything.
      d_->document = r.string("document", true).value_or("");
      if (auto v = r.integer("demo_rpm", 1, 32767, false))
        d_->demo_rpm = static_cast<std::int32_t>(*v);
    });
  }

  void read_line(TableReader& top) {
    top.read_table("line", true, [&](TableReader& r) {
      r.expect({"baud", "parity", "data_bits", "stop_bits", "echo", "streaming", "address"});
      LineDefaults& l = d_->line;
      if (auto v = r.integer("baud", 50, 4'000'000, true)) l.baud = static_cast<std::uint32_t>(*v);
      if (auto p = r.choice("parity", kParityNames, false)) l.parity = static_cast<Parity>(*p);
      if (auto v = r.integer("data_bits", 5, 8, false)) l.data_bits = static_cast<std::uint8_t>(*v);
      if (auto v = r.integer("stop_bits", 1, 2, false)) l.stop_bits = static_cast<std::uint8_t>(*v);
      l.echo = r.boolean("echo").value_or(false);
      d_->streaming = r.boolean("streaming").value_or(false);
      if (const toml::table* a = r.table("address", false)) {
        TableReader ar(*a, "line.address", diag_);
        ar.expect({"min", "max", "default"});
        const auto lo = ar.integer("min", 0, 0xFFFF, true);
        const auto hi = ar.integer("max", 1, 0xFFFF, true);
        const auto def = ar.integer("default", 0, 0xFFFF, true);
        if (lo && hi && def) {
          if (*lo > *hi || *def < *lo || *def > *hi) {
            diag_.error(a, "line.address", "needs min <= default <= max");
          } else {
            d_->address_min = static_cast<std::uint32_t>(*lo);
            d_->address_max = static_cast<std::uint32_t>(*hi);
            d_->address_default = static_cast<std::uint32_t>(*def);
          }
        }
      }
    });
  }

  std::optional<std::uint8_t> byte_at(TableReader& r, std::string_view key) {
    if (auto v = r.integer(key, 0, 255, false)) return static_cast<std::uint8_t>(*v);
    return std::nullopt;
  }

  void read_framing(TableReader& top) {
    top.read_table("framing", false, [&](TableReader& r, const toml::table* t) {
      r.expect({"max_frame", "start", "end", "escape", "escaped", "escape_xor"});
      Framing& f = d_->framing;
      if (auto v = r.integer("max_frame", 2, static_cast<std::int64_t>(kMaxFrame), false)) {
        f.max_frame = static_cast<std::size_t>(*v);
      }
      f.start = byte_at(r, "start");
      f.end = byte_at(r, "end");
      f.escape = byte_at(r, "escape");
      if (auto v = byte_at(r, "escape_xor")) f.escape_xor = *v;
      if (const toml::node* n = r.node("escaped")) {
        const auto* a = n->as_array();
        bool ok = a != nullptr;
        if (ok) {
          for (const auto& item : *a) {
            const auto* i = item.as_integer();
            if (i == nullptr || i->get() < 0 || i->get() > 255) {
              ok = false;
              break;
            }
            f.escaped.push_back(static_cast<std::uint8_t>(i->get()));
          }
        }
        if (!ok) diag_.error(n, "framing.escaped", "must be a list of bytes (0..255)");
      }
      if (f.end && !f.start) diag_.error(t, "framing", "an end flag needs a start flag");
      if (f.escape && !f.start) diag_.error(t, "framing", "stuffing needs start and end flags");
      if (f.start && f.escape) {
        // Every byte that means something on the line must be sent escaped inside a frame.
        for (const std::uint8_t must : {*f.start, f.end.value_or(*f.start), *f.escape}) {
          if (std::find(f.escaped.begin(), f.escaped.end(), must) == f.escaped.end()) {
            diag_.error(t, "framing.escaped",
                        "must hold the flags and the escape byte (missing " + hex(must) + ")");
          }
        }
      }
      if (f.start && !f.escape) {
        diag_.error(t, "framing",
                    "start and end flags need an escape byte: a flag inside a frame "
                    "would end it");
      }
    });
  }

  static std::string hex(unsigned v) {
    static const char* digits = "0123456789ABCDEF";
    std::string s = "0x";
    s += digits[(v >> 4) & 0xF];
    s += digits[v & 0xF];
    return s;
  }

  void read_timing(TableReader& top) {
    top.read_table("timing", false, [&](TableReader& r) {
      r.expect({"reply_timeout_ms", "attempts", "comm_timeout_ms", "gap_ms", "confirm_ms",
                "poll_ms", "writes_before_ready"});
      Timing& tm = d_->timing;
      if (auto e = expr(r, "reply_timeout_ms")) tm.reply_timeout_ms = std::move(*e);
      if (auto e = expr(r, "attempts")) tm.attempts = std::move(*e);
      if (auto e = expr(r, "comm_timeout_ms")) tm.comm_timeout_ms = std::move(*e);
      if (auto e = expr(r, "gap_ms")) tm.gap_ms = std::move(*e);
      if (auto e = expr(r, "confirm_ms")) tm.confirm_ms = std::move(*e);
      if (const toml::table* p = r.table("poll_ms", false)) {
        TableReader pr(*p, "timing.poll_ms", diag_);
        pr.expect({"min", "max"});
        if (auto v = pr.integer("min", 1, 3'600'000, false))
          tm.poll_min_ms = static_cast<double>(*v);
        if (auto v = pr.integer("max", 1, 3'600'000, false))
          tm.poll_max_ms = static_cast<double>(*v);
      }
      if (auto w = r.string("writes_before_ready", false)) {
        if (*w == "wait" || *w == "refuse") {
          tm.writes_wait_for_ready = *w == "wait";
        } else {
          diag_.error(r.node("writes_before_ready"), "timing.writes_before_ready",
                      "must be wait or refuse");
        }
      }
    });
  }

  // ---- checks and tables -------------------------------------------------------------------

  void read_checks(TableReader& top) {
    const toml::table* t = top.table("check", false);
    if (t == nullptr) return;
    for (const auto& [k, node] : *t) {
      const std::string name(k.str());
      const std::string key = "check." + name;
      const auto* ct = node.as_table();
      if (ct == nullptr) {
        diag_.error(&node, key, "must be a table");
        continue;
      }
      if (!valid_name(name) || is_type_name(name)) {
        diag_.error(&node, key, "'" + name + "' is not a check name (snake_case, not a type)");
        continue;
      }
      TableReader r(*ct, key, diag_);
      r.expect({"kind", "width", "order", "total", "poly", "init", "reflect_in", "reflect_out",
                "xor_out", "from", "to", "step"});
      Check c;
      c.name = name;
      c.line = line_of_node(&node);
      if (auto kind = r.choice("kind", kCheckKindNames, true))
        c.kind = static_cast<CheckKind>(*kind);
      const std::int64_t width_default = c.kind == CheckKind::crc ? 2 : 1;
      const auto width = r.integer("width", 1, 4, false).value_or(width_default);
      if (width == 3) diag_.error(r.node("width"), key + ".width", "must be 1, 2 or 4 bytes");
      c.width = static_cast<std::uint8_t>(width);
      if (auto o = r.string("order", false)) {
        if (*o != "big" && *o != "little") {
          diag_.error(r.node("order"), key + ".order", "must be big or little");
        }
        c.little_endian = *o == "little";
      }
      const std::int64_t top_value = width == 4 ? 0xFFFFFFFFLL : (1LL << (8 * width)) - 1;
      if (auto v = r.integer("total", 0, top_value, c.kind == CheckKind::sum_to)) {
        c.total = static_cast<std::uint32_t>(*v);
      }
      if (c.kind == CheckKind::crc) {
        if (auto v = r.integer("poly", 1, top_value, true)) c.poly = static_cast<std::uint32_t>(*v);
        if (auto v = r.integer("init", 0, top_value, false))
          c.init = static_cast<std::uint32_t>(*v);
        if (auto v = r.integer("xor_out", 0, top_value, false))
          c.xor_out = static_cast<std::uint32_t>(*v);
        c.reflect_in = r.boolean("reflect_in").value_or(false);
        c.reflect_out = r.boolean("reflect_out").value_or(false);
      } else if (c.kind == CheckKind::lrc && width != 1) {
        diag_.error(ct, key + ".width", "an LRC is one byte");
      }
      if (auto v = r.integer("from", -static_cast<std::int64_t>(kMaxFrame), kMaxFrame, false))
        c.from = static_cast<int>(*v);
      if (auto v = r.integer("to", -static_cast<std::int64_t>(kMaxFrame), kMaxFrame, false))
        c.to = static_cast<int>(*v);
      if (auto v = r.integer("step", 1, 8, false)) c.step = static_cast<std::uint8_t>(*v);
      d_->checks.push_back(std::move(c));
    }
  }

  void read_tables(TableReader& top) {
    const toml::table* t = top.table("table", false);
    if (t == nullptr) return;
    for (const auto& [k, v] : *t) {
      const std::string name(k.str());
      const std::string key = "table." + name;
      if (!declare(&v, key, name)) continue;
      const auto* tt = v.as_table();
      if (tt == nullptr) {
        diag_.error(&v, key, "must be a table with values = [...]");
        continue;
      }
      TableReader r(*tt, key, diag_);
      r.expect({"values"});
      Table table;
      table.name = name;
      table.line = line_of_node(&v);
      const toml::node* vn = r.node("values");
      const auto* a = vn != nullptr ? vn->as_array() : nullptr;
      if (a == nullptr || a->empty()) {
        diag_.error(vn != nullptr ? vn : tt, key + ".values", "must be a list of numbers");
        continue;
      }
      for (const auto& item : *a) {
        if (const auto* i = item.as_integer()) {
          table.values.push_back(static_cast<double>(i->get()));
        } else if (const auto* f = item.as_floating_point()) {
          table.values.push_back(f->get());
        } else {
          diag_.error(&item, key + ".values", "must be a list of numbers");
          break;
        }
      }
      d_->tables.push_back(std::move(table));
    }
  }

  // ---- variables ---------------------------------------------------------------------------

  void add_builtins() {
    const auto add = [&](std::string name, double value) {
      Var v;
      v.name = std::move(name);
      v.kind = Var::Kind::builtin;
      v.initial = Val::of(value);
      taken_.insert(v.name);
      d_->vars.push_back(std::move(v));
    };
    add("command", 0);
    add("setpoint", 0);
    add("address", 0);
    add("poll_ms", 500);
    add("value", 0);
    add("dt_ms", 0);
    add("sequence", 0);
    for (std::size_t c = 0; c < kCommandNames.size(); ++c) {
      add(std::string(kCommandNames[c]), static_cast<double>(c));
    }
    add("true", 1);
    add("false", 0);
  }

  void read_options(TableReader& top) {
    top.read_each("option", [&](TableReader& r, const toml::table& t) {
      expect_read(r, {"name", "type", "default", "min", "max", "choices", "description"});
      Option o;
      o.line = line_of_node(&t);
      const auto name = r.string("name", true);
      if (!name) return;
      if (*name == "protocol") {
        diag_.error(r.node("name"), "option.name", "'protocol' names the description itself");
        return;
      }
      if (!valid_name(*name) || !option_names_.insert(*name).second) {
        diag_.error(r.node("name"), "option.name",
                    "'" + *name + "' is not a name, or is another option's");
        return;
      }
      o.name = *name;
      o.type = static_cast<OptionType>(r.choice("type", kOptionTypeNames, true).value_or(0));
      o.description = r.string("description", true).value_or("");
      const toml::node* def = r.node("default");
      if (def == nullptr) {
        r.missing("default");  // every option has one, so a driver never meets a missing one
      } else if (const auto* i = def->as_integer()) {
        o.default_text = std::to_string(i->get());
      } else if (const auto* f = def->as_floating_point()) {
        o.default_text = std::to_string(f->get());
      } else if (const auto* b = def->as_boolean()) {
        o.default_text = b->get() ? "true" : "false";
      } else if (const auto* s = def->as_string()) {
        o.default_text = s->get();
      } else {
        diag_.error(def, "option.default", "must be a number, true or false, or a text");
      }
      if (auto v = r.number("min", -1e15, 1e15, false)) o.min = *v;
      if (auto v = r.number("max", -1e15, 1e15, false)) o.max = *v;
      o.choices = r.string("choices", false).value_or("");
      Var v;
      v.name = "option." + o.name;  // options are read as option.NAME
      v.kind = Var::Kind::option;
      v.line = o.line;
      o.var = d_->vars.size();
      d_->vars.push_back(std::move(v));
      d_->options.push_back(std::move(o));
    });
  }

  void read_states(TableReader& top) {
    top.read_each("state", [&](TableReader& r, const toml::table& t) {
      expect_read(r, {"name", "initial", "comm_lost", "description"});
      const auto name = r.string("name", true);
      if (!name || !declare(r.node("name"), "state.name", *name)) return;
      Var v;
      v.name = *name;
      v.kind = Var::Kind::state;
      v.line = line_of_node(&t);
      (void)r.string("description", false);
      r.node("initial");  // read in compile_points(), once every name is known
      r.node("comm_lost");
      pending_state_.emplace_back(d_->vars.size(), &t);
      d_->vars.push_back(std::move(v));
    });
  }

  // ---- points ------------------------------------------------------------------------------

  void read_labels(TableReader& r, PointSpec& p, const std::string& key) {
    const toml::node* vl = r.node("labels");
    const toml::node* bl = r.node("bit_labels");
    if (vl != nullptr && bl != nullptr) {
      diag_.error(bl, key + ".bit_labels", "a point has labels or bit_labels, not both");
      return;
    }
    const toml::node* n = vl != nullptr ? vl : bl;
    if (n == nullptr) return;
    p.bit_labels = bl != nullptr;
    const auto* a = n->as_array();
    if (a == nullptr) {
      diag_.error(n, key, "labels must be a list of names, or of [value, name] pairs");
      return;
    }
    std::uint32_t next = 0;
    for (const auto& item : *a) {
      if (const auto* s = item.as_string()) {
        p.labels.push_back({s->get(), next++});
        continue;
      }
      const auto* pair = item.as_array();
      const toml::node* v = pair != nullptr && pair->size() == 2 ? pair->get(0) : nullptr;
      const toml::node* s = pair != nullptr && pair->size() == 2 ? pair->get(1) : nullptr;
      if (v == nullptr || v->as_integer() == nullptr || s == nullptr || s->as_string() == nullptr ||
          v->as_integer()->get() < 0 || v->as_integer()->get() > 0xFFFFFFFFLL) {
        diag_.error(&item, key, "labels must be a list of names, or of [value, name] pairs");
        return;
      }
      const auto value = static_cast<std::uint32_t>(v->as_integer()->get());
      p.labels.push_back({s->as_string()->get(), value});
      next = value + 1;
    }
  }

  // Declares the keys `r` may have and marks each as read: an entry given up early does not also
  // report its keys.
  static void expect_read(TableReader& r, std::initializer_list<std::string_view> keys) {
    r.expect(keys);
    for (const auto k : keys) r.node(k);
  }

  void read_points(TableReader& top) {
    top.read_each("point", [&](TableReader& r, const toml::table& t) {
      expect_read(r, {"name", "table", "type", "scale", "unit", "description", "labels",
                      "bit_labels", "min", "max", "access", "trend", "registers", "initial",
                      "value", "on_write", "status", "comm_lost"});
      Point p;
      p.line = line_of_node(&t);
      const auto name = r.string("name", true);
      if (!name || !declare(r.node("name"), "point.name", *name)) return;
      p.spec.name = *name;
      if (auto tb = r.choice("table", kTableNames, true))
        p.spec.table = static_cast<drivegate::Table>(*tb);
      // The register map's types up to string: a description's values are not 64 bits wide.
      constexpr std::array<std::string_view, 6> kTypes = {kPointTypeNames[0], kPointTypeNames[1],
                                                          kPointTypeNames[2], kPointTypeNames[3],
                                                          kPointTypeNames[4], kPointTypeNames[5]};
      if (auto ty = r.choice("type", kTypes, true)) p.spec.type = static_cast<PointType>(*ty);
      if (auto s = r.number("scale", -1e9, 1e9, false)) {
        if (*s == 0.0) diag_.error(r.node("scale"), "point.scale", "must not be 0");
        p.spec.scale = *s;
      }
      p.spec.unit = r.string("unit", false).value_or("");
      p.spec.description = r.string("description", true).value_or("");
      read_labels(r, p.spec, "point.labels");
      const bool writable =
          p.spec.table == drivegate::Table::holding || p.spec.table == drivegate::Table::coil;
      const auto lo = r.number("min", -1e15, 1e15, false);
      const auto hi = r.number("max", -1e15, 1e15, false);
      if ((lo || hi) && !writable) {
        diag_.error(r.node(lo ? "min" : "max"), "point.min",
                    "limits are for what a client writes: holding registers and coils");
      }
      if (writable && (!lo || !hi)) {
        diag_.error(&t, "point." + *name,
                    "a writable point needs min and max: what a client may write is checked "
                    "before anything is sent");
      }
      if (lo && hi) {
        if (*lo > *hi) diag_.error(r.node("min"), "point.min", "must not exceed max");
        p.spec.limited(*lo, *hi);
      }
      if (auto acc = r.choice("access", kAccessNames, false)) {
        p.spec.write_level = static_cast<PointSpec::WriteLevel>(*acc);
      }
      p.spec.trend = r.boolean("trend").value_or(false);
      if (p.spec.type == PointType::string) {
        if (auto v = r.integer("registers", 1, 125, true)) {
          p.spec.string_registers = static_cast<std::uint16_t>(*v);
        }
      }
      for (const char* k : {"initial", "value", "on_write", "status", "comm_lost"}) r.node(k);
      Var v;
      v.name = *name;
      v.kind = Var::Kind::point;
      v.point = d_->points.size();
      v.line = p.line;
      p.var = d_->vars.size();
      d_->vars.push_back(std::move(v));
      pending_points_.push_back(&t);
      d_->points.push_back(std::move(p));
    });
  }

  // ---- messages ----------------------------------------------------------------------------

  static bool is_type_name(std::string_view s) {
    static const std::set<std::string_view> kTypes = {
        "u8",    "u16",   "u24",   "u32",   "i8",    "i16",   "i24",  "i32",  "f32",  "u16le",
        "u24le", "u32le", "i16le", "i24le", "i32le", "f32le", "bcd1", "bcd2", "bcd3", "bcd4"};
    return kTypes.contains(s);
  }

  // A field's type: u8..u32, i8..i32, f32 (le: low byte first), bcd1..bcd4.
  static bool field_type(std::string_view s, Token& t) {
    if (!is_type_name(s)) return false;
    t.little_endian = s.ends_with("le");
    if (t.little_endian) s.remove_suffix(2);
    if (s.starts_with("bcd")) {
      t.encoding = Encoding::bcd;
      t.width = static_cast<std::uint8_t>(s[3] - '0');
      return true;
    }
    t.encoding = s[0] == 'u'   ? Encoding::unsigned_int
                 : s[0] == 'i' ? Encoding::signed_int
                               : Encoding::f32;
    const int bits = std::atoi(std::string(s.substr(1)).c_str());
    t.width = static_cast<std::uint8_t>(bits / 8);
    return true;
  }

  static bool hex_byte(std::string_view s, std::uint8_t& out) {
    if (s.size() != 2) return false;
    unsigned v = 0;
    for (const char c : s) {
      v <<= 4;
      if (c >= '0' && c <= '9')
        v |= static_cast<unsigned>(c - '0');
      else if (c >= 'A' && c <= 'F')
        v |= static_cast<unsigned>(c - 'A' + 10);
      else if (c >= 'a' && c <= 'f')
        v |= static_cast<unsigned>(c - 'a' + 10);
      else
        return false;
    }
    out = static_cast<std::uint8_t>(v);
    return true;
  }

  // "A5 mode:u8 speed:u16 00 x:xor": the tokens of a layout, in order.
  bool parse_layout(std::string_view text, Message& m, std::string& error) {
    std::size_t offset = 0;
    std::size_t i = 0;
    int index = 0;
    while (i < text.size()) {
      while (i < text.size() && (text[i] == ' ' || text[i] == '\t' || text[i] == '\n')) ++i;
      const std::size_t start = i;
      while (i < text.size() && text[i] != ' ' && text[i] != '\t' && text[i] != '\n') ++i;
      if (i == start) break;
      const std::string_view tok = text.substr(start, i - start);
      ++index;
      const std::string where = "token " + std::to_string(index) + " '" + std::string(tok) + "'";
      Token t;
      t.offset = offset;
      const auto colon = tok.find(':');
      if (colon == std::string_view::npos) {
        if (!hex_byte(tok, t.byte)) {
          error = where + ": a constant byte is two hex digits (A5); a field is name:type";
          return false;
        }
        t.kind = Token::Kind::constant;
        t.width = 1;
      } else {
        const std::string name(tok.substr(0, colon));
        const std::string_view type = tok.substr(colon + 1);
        if (!valid_name(name)) {
          error = where + ": '" + name + "' is not a field name (a-z first, then a-z, 0-9, '_')";
          return false;
        }
        if (std::any_of(m.fields.begin(), m.fields.end(),
                        [&](const Field& f) { return f.name == name; })) {
          error = where + ": the message has a field '" + name + "' already";
          return false;
        }
        const auto check = std::find_if(d_->checks.begin(), d_->checks.end(),
                                        [&](const Check& c) { return c.name == type; });
        if (check != d_->checks.end()) {
          t.kind = Token::Kind::check;
          t.name = name;
          t.check = static_cast<std::size_t>(check - d_->checks.begin());
          t.width = check->width;
          t.little_endian = check->little_endian;
        } else if (field_type(type, t)) {
          t.kind = Token::Kind::field;
        } else {
          error = where + ": unknown type '" + std::string(type) +
                  "' (u8, u16, u24, u32, i8..i32, f32, each with le for low byte first; "
                  "bcd1..bcd4; or a [check] name)";
          return false;
        }
        if (t.kind == Token::Kind::field) {
          Field f;
          f.name = name;
          const auto id = field_id(name);
          f.global = id.value_or(d_->field_names.size());
          if (!id) d_->field_names.push_back(name);
          t.field = m.fields.size();
          m.fields.push_back(std::move(f));
          if (m.fields.size() > kMaxFields) {
            error = "more than " + std::to_string(kMaxFields) + " fields";
            return false;
          }
        } else {
          // A check's name is a field of the dissector's, not of the message.
        }
      }
      offset += t.width;
      m.tokens.push_back(t);
    }
    if (m.tokens.empty()) {
      error = "a layout needs at least one byte";
      return false;
    }
    m.size = offset;
    return true;
  }

  std::optional<std::string> frame_layout(const toml::table* frames, const std::string& name,
                                          const toml::node* at) {
    const toml::node* f = frames != nullptr ? frames->get(name) : nullptr;
    const auto* ft = f != nullptr ? f->as_table() : nullptr;
    const toml::node* l = ft != nullptr ? ft->get("layout") : nullptr;
    if (l == nullptr || l->as_string() == nullptr) {
      diag_.error(at, "message.frame", "no [frame." + name + "] with a layout");
      return std::nullopt;
    }
    return l->as_string()->get();
  }

  void read_frames(TableReader& top) {
    const toml::table* t = top.table("frame", false);
    frames_ = t;
    if (t == nullptr) return;
    for (const auto& [k, v] : *t) {
      const std::string key = "frame." + std::string(k.str());
      const auto* ft = v.as_table();
      if (ft == nullptr) {
        diag_.error(&v, key, "must be a table");
        continue;
      }
      TableReader r(*ft, key, diag_);
      r.expect({"layout", "values", "length"});
      const auto layout = r.string("layout", true);
      if (layout && layout->find("{body}") == std::string::npos) {
        diag_.error(r.node("layout"), key + ".layout", "a frame's layout holds {body}");
      }
      r.node("values");
      r.node("length");
    }
  }

  void read_messages(TableReader& top) {
    read_frames(top);
    const bool any = top.read_each("message", [&](TableReader& r, const toml::table& t) {
      expect_read(r, {"name", "summary", "direction", "layout", "frame", "body", "values", "limits",
                      "length", "replies", "echo", "nack", "unsolicited", "state", "update", "sent",
                      "timeout_ms", "attempts"});
      Message m;
      m.line = line_of_node(&t);
      const auto name = r.string("name", true);
      if (!name) return;
      if (!valid_name(*name) || d_->message(*name)) {
        diag_.error(r.node("name"), "message.name",
                    "'" + *name + "' is not a name, or is another message's");
        return;
      }
      m.name = *name;
      m.summary = r.string("summary", false).value_or("");
      m.direction =
          static_cast<Direction>(r.choice("direction", kDirectionNames, true).value_or(0));
      const auto layout = r.string("layout", false);
      const auto frame = r.string("frame", false);
      const auto body = r.string("body", false);
      std::string text;
      if (layout && !frame && !body) {
        text = *layout;
      } else if (!layout && frame && body) {
        const auto envelope = frame_layout(frames_, *frame, r.node("frame"));
        if (!envelope) return;
        text = *envelope;
        text.replace(text.find("{body}"), 6, *body);
        m_frame_[d_->messages.size()] = *frame;
      } else {
        diag_.error(&t, "message." + *name, "needs a layout, or a frame and a body");
        return;
      }
      std::string why;
      if (!parse_layout(text, m, why)) {
        diag_.error(r.node(layout ? "layout" : "body"), "message." + *name + ".layout", why);
        return;
      }
      if (m.size > d_->framing.max_frame) {
        diag_.error(&t, "message." + *name,
                    std::to_string(m.size) + " bytes: longer than framing.max_frame (" +
                        std::to_string(d_->framing.max_frame) + ")");
      }
      m.nack = r.boolean("nack").value_or(false);
      m.unsolicited = r.boolean("unsolicited").value_or(false);
      m.state = r.boolean("state").value_or(!m.nack);
      if ((m.nack || m.unsolicited) && m.direction != Direction::reply) {
        diag_.error(&t, "message." + *name, "nack and unsolicited are for replies");
      }
      for (const char* k : {"values", "limits", "length", "replies", "echo", "update", "sent",
                            "timeout_ms", "attempts"}) {
        r.node(k);  // read in compile_messages(), once every message is known
      }
      pending_messages_.push_back(&t);
      d_->messages.push_back(std::move(m));
    });
    if (!any) diag_.error_at(0, "message", "a description needs at least one [[message]]");
  }

  void read_length(Message& m, const toml::node* n, const std::string& key) {
    const auto* t = n->as_table();
    if (t == nullptr) {
      diag_.error(n, key, "must be a table such as { field = \"n\", counts = \"payload\" }");
      return;
    }
    TableReader r(*t, key, diag_);
    r.expect({"field", "counts", "offset"});
    Length len;
    const auto field = r.string("field", true);
    if (!field) return;
    const auto f = std::find_if(m.fields.begin(), m.fields.end(),
                                [&](const Field& x) { return x.name == *field; });
    if (f == m.fields.end()) {
      diag_.error(r.node("field"), key + ".field", "no field '" + *field + "' in the layout");
      return;
    }
    len.field = static_cast<std::size_t>(f - m.fields.begin());
    if (auto c = r.choice("counts", kCountsNames, false))
      len.counts = static_cast<Length::Counts>(*c);
    if (auto o = r.integer("offset", -16, 16, false)) len.offset = static_cast<int>(*o);
    // Every layout has a fixed size: the length field holds one value, checked on receipt.
    const Token* lt = nullptr;
    std::size_t first_check = m.size;
    for (const Token& tok : m.tokens) {
      if (tok.kind == Token::Kind::field && tok.field == len.field) lt = &tok;
      if (tok.kind == Token::Kind::check) first_check = std::min(first_check, tok.offset);
    }
    std::size_t counted = m.size;
    if (len.counts == Length::Counts::payload) counted = first_check - (lt->offset + lt->width);
    if (len.counts == Length::Counts::rest) counted = m.size - (lt->offset + lt->width);
    if (first_check < lt->offset && len.counts == Length::Counts::payload) counted = 0;
    m.length_value = static_cast<double>(counted) + len.offset;
    m.length = len;
  }

  void compile_messages(const toml::table& root) {
    (void)root;
    for (std::size_t i = 0; i < d_->messages.size(); ++i) {
      Message& m = d_->messages[i];
      const toml::table& t = *pending_messages_[i];
      const std::string key = "message." + m.name;
      // The envelope's own keys first, the message's over them.
      const toml::table* envelope = nullptr;
      if (const auto f = m_frame_.find(i); f != m_frame_.end() && frames_ != nullptr) {
        envelope = frames_->get(f->second)->as_table();
      }
      const auto node = [&](const char* k) -> const toml::node* {
        if (const toml::node* n = t.get(k)) return n;
        return envelope != nullptr ? envelope->get(k) : nullptr;
      };
      if (const toml::node* n = node("length")) read_length(m, n, key + ".length");
      // Limits: a received value outside is not this message.
      if (const toml::node* n = t.get("limits")) {
        const auto* lt = n->as_table();
        if (lt == nullptr) diag_.error(n, key + ".limits", "must be a table of [min, max]");
        for (const auto& [k, v] : lt != nullptr ? *lt : toml::table{}) {
          const std::string_view name = k.str();  // clang 14 captures no structured binding
          const auto f = std::find_if(m.fields.begin(), m.fields.end(),
                                      [&](const Field& x) { return x.name == name; });
          const auto* pair = v.as_array();
          if (f == m.fields.end() || pair == nullptr || pair->size() != 2 ||
              !pair->get(0)->is_number() || !pair->get(1)->is_number()) {
            diag_.error(&v, key + ".limits." + std::string(k.str()),
                        "must name a field of the layout and give [min, max]");
            continue;
          }
          f->min = pair->get(0)->value<double>();
          f->max = pair->get(1)->value<double>();
        }
      }
      // Values sent: the expression given, else the variable of the field's name (a point's
      // register value, a state, option.NAME), else 0.
      const toml::table* values = nullptr;
      if (const toml::node* n = t.get("values")) {
        values = n->as_table();
        if (values == nullptr) diag_.error(n, key + ".values", "must be a table of expressions");
      }
      const toml::table* env_values = envelope != nullptr && envelope->get("values") != nullptr
                                          ? envelope->get("values")->as_table()
                                          : nullptr;
      Context ctx;
      ctx.sent = m.direction == Direction::reply;  // a reply (the simulator's) reads its request
      for (const toml::table* vt : {values, env_values}) {
        if (vt == nullptr) continue;
        for (const auto& [k, v] : *vt) {
          const std::string_view name = k.str();  // clang 14 captures no structured binding
          const auto f = std::find_if(m.fields.begin(), m.fields.end(),
                                      [&](const Field& x) { return x.name == name; });
          if (f == m.fields.end()) {
            if (vt == values) {
              diag_.error(&v, key + ".values." + std::string(k.str()),
                          "no field '" + std::string(k.str()) + "' in the layout");
            }
            continue;
          }
          if (f->has_value) continue;
          if (auto e = expr(&v, key + ".values." + std::string(k.str()), ctx)) {
            f->value = std::move(*e);
            f->has_value = true;
          }
        }
      }
      for (Field& f : m.fields) {
        if (f.has_value) continue;
        std::string why;
        std::string own = f.name;
        if (const auto v = var_of(f.name); v && d_->vars[*v].kind == Var::Kind::point) {
          // A point's register value: its engineering value over its scale.
          const double scale = d_->points[d_->vars[*v].point].spec.scale;
          if (scale != 1.0) own = f.name + " / " + number_text(scale);
        }
        for (const std::string& name : {own, "option." + f.name}) {
          auto e = Expr::compile(name, names_for({}), why);
          if (e) {
            f.value = std::move(*e);
            f.has_value = true;
            break;
          }
        }
        if (!f.has_value) f.value = Expr::number(0);
      }
    }
    // Replies and echoes, once every message is known.
    for (std::size_t i = 0; i < d_->messages.size(); ++i) {
      Message& m = d_->messages[i];
      const toml::table& t = *pending_messages_[i];
      const std::string key = "message." + m.name;
      if (const toml::node* n = t.get("replies")) {
        const auto* a = n->as_array();
        if (a == nullptr || m.direction != Direction::request) {
          diag_.error(n, key + ".replies", "a request's replies are a list of message names");
        }
        for (const auto& item : a != nullptr ? *a : toml::array{}) {
          const auto* s = item.as_string();
          const auto reply = s != nullptr ? d_->message(s->get()) : std::nullopt;
          if (!reply || d_->messages[*reply].direction != Direction::reply) {
            diag_.error(&item, key + ".replies", "must name reply messages");
            continue;
          }
          m.replies.push_back(*reply);
        }
      }
      if (auto e = expr(t.get("timeout_ms"), key + ".timeout_ms"))
        m.reply_timeout_ms = std::move(*e);
      if (auto e = expr(t.get("attempts"), key + ".attempts")) m.attempts = std::move(*e);
      if (const toml::node* n = t.get("sent")) {
        Context own;
        own.own = &m;
        m.update = assignments(n, key + ".sent", own);
        if (m.direction != Direction::request) {
          diag_.error(n, key + ".sent", "only a request is sent");
        }
      }
    }
    for (std::size_t i = 0; i < d_->messages.size(); ++i) {
      Message& m = d_->messages[i];
      const toml::table& t = *pending_messages_[i];
      const std::string key = "message." + m.name;
      if (m.direction != Direction::reply) continue;
      if (const toml::node* n = t.get("echo")) {
        const auto* a = n->as_array();
        if (a == nullptr) diag_.error(n, key + ".echo", "must be a list of field names");
        for (const auto& item : a != nullptr ? *a : toml::array{}) {
          const auto* s = item.as_string();
          const auto f = s == nullptr
                             ? m.fields.end()
                             : std::find_if(m.fields.begin(), m.fields.end(),
                                            [&](const Field& x) { return x.name == s->get(); });
          if (f == m.fields.end()) {
            diag_.error(&item, key + ".echo", "must name fields of the layout");
            continue;
          }
          m.echo.emplace_back(static_cast<std::size_t>(f - m.fields.begin()), f->global);
        }
      }
      Context own;
      own.own = &m;
      own.sent = true;
      std::vector<Assign> explicit_updates;
      if (const toml::node* n = t.get("update"))
        explicit_updates = assignments(n, key + ".update", own);
      // A field named after a point or a state updates it (a point's register value), unless an
      // assignment of the message's says otherwise.
      for (const Field& f : m.fields) {
        const auto v = var_of(f.name);
        if (!v || (d_->vars[*v].kind != Var::Kind::point && d_->vars[*v].kind != Var::Kind::state))
          continue;
        if (std::any_of(explicit_updates.begin(), explicit_updates.end(),
                        [&](const Assign& a) { return a.target == *v; }))
          continue;
        std::string why;
        const Var& var = d_->vars[*v];
        std::string text = f.name;
        if (var.kind == Var::Kind::point) {
          const double scale = d_->points[var.point].spec.scale;
          if (scale != 1.0) text += " * " + number_text(scale);
        }
        if (auto e = Expr::compile(text, names_for(own), why))
          m.update.push_back({*v, std::move(*e)});
      }
      for (Assign& a : explicit_updates) m.update.push_back(std::move(a));
    }
  }

  static std::string number_text(double v) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
  }

  // ---- point and state expressions ---------------------------------------------------------

  void compile_points(const toml::table& root) {
    (void)root;
    for (const auto& [index, t] : pending_state_) {
      Var& v = d_->vars[index];
      const std::string key = "state." + v.name;
      if (auto e = expr(t->get("initial"), key + ".initial")) {
        if (const auto c = e->constant())
          v.initial = Val::of(*c);
        else
          v.initial_expr = std::move(*e);
      }
      if (const toml::node* n = t->get("comm_lost")) {
        if (auto e = expr(n, key + ".comm_lost"); e && e->constant()) {
          v.reset_on_comm_lost = true;
          v.reset_value = Val::of(*e->constant());
        } else {
          diag_.error(n, key + ".comm_lost", "must be a number");
        }
      }
    }
    for (std::size_t i = 0; i < d_->points.size(); ++i) {
      Point& p = d_->points[i];
      const toml::table& t = *pending_points_[i];
      const std::string key = "point." + p.spec.name;
      if (auto e = expr(t.get("initial"), key + ".initial"))
        d_->vars[p.var].initial_expr = std::move(*e);
      if (const toml::node* n = t.get("comm_lost")) {
        if (auto e = expr(n, key + ".comm_lost"); e && e->constant()) {
          d_->vars[p.var].reset_on_comm_lost = true;
          d_->vars[p.var].reset_value = Val::of(*e->constant());
        } else {
          diag_.error(n, key + ".comm_lost", "must be a number");
        }
      }
      if (auto e = expr(t.get("value"), key + ".value")) p.value = std::move(*e);
      if (const toml::node* n = t.get("status")) {
        const auto* s = n->as_string();
        const auto v = s != nullptr ? var_of(s->get()) : std::nullopt;
        if (!v || d_->vars[*v].kind != Var::Kind::point ||
            d_->points[d_->vars[*v].point].spec.table != drivegate::Table::input) {
          diag_.error(n, key + ".status", "must name an input point");
        } else {
          p.status = d_->vars[*v].point;
        }
      }
      if (const toml::node* n = t.get("on_write")) {
        const auto* a = n->as_array();
        if (a == nullptr) diag_.error(n, key + ".on_write", "must be a list of { when, send }");
        for (const auto& item : a != nullptr ? *a : toml::array{}) {
          const auto* wt = item.as_table();
          if (wt == nullptr) {
            diag_.error(&item, key + ".on_write", "must be a list of { when, send }");
            continue;
          }
          TableReader r(*wt, key + ".on_write", diag_);
          r.expect({"when", "send", "accept"});
          Point::OnWrite w;
          w.when = expr(r, "when");
          w.send = message_ref(r, "send", Direction::request, false);
          Context ctx;
          if (w.send) {
            for (const std::size_t rep : d_->messages[*w.send].replies) {
              ctx.frames.push_back(&d_->messages[rep]);
            }
            ctx.sent = true;
          }
          w.accept = expr(r, "accept", ctx);
          p.on_write.push_back(std::move(w));
        }
        if (p.spec.table != drivegate::Table::holding && p.spec.table != drivegate::Table::coil) {
          diag_.error(n, key + ".on_write", "only a holding register or a coil is written");
        }
      }
    }
  }

  // ---- behaviour ---------------------------------------------------------------------------

  void read_periodic(TableReader& top, const char* key, std::optional<Periodic>& out) {
    top.read_table(key, false, [&](TableReader& r) {
      r.expect({"send", "every_ms", "when", "at_ready"});
      const auto send = message_ref(r, "send", Direction::request, true);
      if (!send) return;
      Periodic p;
      p.send = *send;
      p.every_ms = expr(r, "every_ms");
      p.when = expr(r, "when");
      p.at_ready = r.boolean("at_ready").value_or(false);
      out = std::move(p);
    });
  }

  Context reply_context(std::optional<std::size_t> send) {
    Context ctx;
    if (send) {
      for (const std::size_t rep : d_->messages[*send].replies) {
        ctx.frames.push_back(&d_->messages[rep]);
      }
      ctx.sent = true;
    }
    return ctx;
  }

  void read_commands(TableReader& top) {
    const toml::table* t = top.table("command", false);
    if (t == nullptr) return;
    for (const auto& [k, v] : *t) {
      const std::string name(k.str());
      const std::string key = "command." + name;
      const auto c = index_of(kCommandNames, name);
      if (!c) {
        diag_.error(&v, key,
                    "no command '" + name + "' (" + TableReader::names_text(kCommandNames) + ")");
        continue;
      }
      const auto* a = v.as_array();
      if (a == nullptr || !a->is_array_of_tables()) {
        diag_.error(&v, key, "must be an array of tables ([[" + key + "]])");
        continue;
      }
      auto& alternatives = d_->commands[static_cast<Command>(*c)];
      for (const auto& item : *a) {
        const auto& at = *item.as_table();
        TableReader r(at, key, diag_);
        r.expect({"when", "invalid", "refuse", "send", "accept", "until", "refuse_on", "becomes"});
        Alternative alt;
        alt.line = line_of_node(&at);
        alt.when = expr(r, "when");
        alt.invalid = expr(r, "invalid");
        alt.refuse = expr(r, "refuse");
        alt.send = message_ref(r, "send", Direction::request, false);
        alt.confirms = r.node("accept") != nullptr || r.node("until") != nullptr;
        alt.accept = expr(r, "accept", reply_context(alt.send));
        alt.until = expr(r, "until");
        alt.refuse_on = expr(r, "refuse_on");
        alt.becomes = static_cast<Command>(*c);
        if (*c == static_cast<std::size_t>(Command::reset_fault)) alt.becomes.reset();
        if (auto b = r.string("becomes", false)) {
          if (*b == "unchanged") {
            alt.becomes.reset();
          } else if (const auto bc = index_of(kCommandNames, *b)) {
            alt.becomes = static_cast<Command>(*bc);
          } else {
            diag_.error(r.node("becomes"), key + ".becomes", "must be a command name or unchanged");
          }
        }
        if (alt.accept && (!alt.send || d_->messages[*alt.send].replies.empty())) {
          diag_.error(r.node("accept"), key + ".accept",
                      "accept judges the reply: the message sent must have replies");
        }
        alternatives.push_back(std::move(alt));
      }
    }
  }

  void read_setpoint(TableReader& top) {
    top.read_table("setpoint", false, [&](TableReader& r, const toml::table* t) {
      r.expect({"min", "max", "invalid", "refuse", "accept", "until", "refuse_on"});
      Setpoint s;
      s.line = line_of_node(t);
      const auto lo = r.number("min", -32768, 65535, false);
      const auto hi = r.number("max", -32768, 65535, false);
      if (lo && hi) {
        if (*lo > *hi) diag_.error(r.node("min"), "setpoint.min", "must not exceed max");
        s.min = *lo;
        s.max = *hi;
        s.limited = true;
      } else if (lo || hi) {
        diag_.error(t, "setpoint", "needs both min and max");
      }
      s.invalid = expr(r, "invalid");
      s.refuse = expr(r, "refuse");
      // The setpoint's frame is the command in force's: its replies are the command's.
      Context any;
      for (const auto& [c, alts] : d_->commands) {
        for (const Alternative& a : alts) {
          if (!a.send) continue;
          for (const std::size_t rep : d_->messages[*a.send].replies) {
            any.frames.push_back(&d_->messages[rep]);
          }
        }
      }
      any.sent = true;
      s.accept = expr(r, "accept", any);
      s.until = expr(r, "until");
      s.refuse_on = expr(r, "refuse_on");
      d_->setpoint = std::move(s);
    });
  }

  void read_unified(TableReader& top) {
    top.read_table("unified", false, [&](TableReader& r) {
      r.expect({"ready", "speed_rpm", "running", "warning", "native_fault", "stops_run",
                "comm_lost_stops"});
      Unified& u = d_->unified;
      u.ready = expr(r, "ready");
      u.speed_rpm = expr(r, "speed_rpm");
      u.running = expr(r, "running");
      u.warning = expr(r, "warning");
      u.native_fault = expr(r, "native_fault");
      u.stops_run = expr(r, "stops_run");
      u.comm_lost_stops = r.boolean("comm_lost_stops").value_or(false);
    });
  }

  std::optional<Fault> fault_at(const toml::node* n, const std::string& key) {
    const auto* s = n != nullptr ? n->as_string() : nullptr;
    if (s != nullptr) {
      if (const auto f = fault_named(s->get()); f && *f != Fault::none) return f;
    }
    diag_.error(n, key,
                "must be a unified fault (" + TableReader::names_text(kFaultNames) + ", not none)");
    return std::nullopt;
  }

  // [[n, "fault"], ...] or [[lo, hi, "fault"], ...]
  template <class Row>
  void fault_rows(const toml::node* n, const std::string& key, std::size_t numbers, Row row) {
    const auto* a = n->as_array();
    if (a == nullptr) {
      diag_.error(n, key, "must be a list of rows");
      return;
    }
    for (const auto& item : *a) {
      const auto* r = item.as_array();
      if (r == nullptr || r->size() != numbers + 1) {
        diag_.error(
            &item, key,
            numbers == 1 ? "rows are [value, \"fault\"]" : "rows are [first, last, \"fault\"]");
        continue;
      }
      std::array<std::uint32_t, 2> v{};
      bool ok = true;
      for (std::size_t i = 0; i < numbers; ++i) {
        const auto* x = r->get(i)->as_integer();
        if (x == nullptr || x->get() < 0 || x->get() > 0xFFFFFFFFLL) {
          ok = false;
        } else {
          v[i] = static_cast<std::uint32_t>(x->get());
        }
      }
      const auto f = fault_at(r->get(numbers), key);
      if (!ok) diag_.error(&item, key, "values are 0..0xFFFFFFFF");
      if (ok && f) row(v, *f);
    }
  }

  void read_faults(TableReader& top) {
    top.read_each("fault", [&](TableReader& r, const toml::table& t) {
      r.expect({"when", "fault", "source", "bits", "values", "ranges", "other"});
      FaultRule rule;
      rule.line = line_of_node(&t);
      rule.when = expr(r, "when");
      rule.source = expr(r, "source");
      if (rule.when.has_value() == rule.source.has_value()) {
        diag_.error(&t, "fault",
                    "a rule has when (and fault) or source (and bits, values or "
                    "ranges), one of the two");
        return;
      }
      if (rule.when) {
        if (auto f = fault_at(r.node("fault"), "fault.fault")) rule.fault = *f;
        continue_if_extra(r, {"bits", "values", "ranges", "other"});
      } else {
        if (const toml::node* b = r.node("bits")) {
          fault_rows(b, "fault.bits", 1, [&](auto v, Fault f) { rule.bits.push_back({v[0], f}); });
        }
        if (const toml::node* b = r.node("values")) {
          fault_rows(b, "fault.values", 1, [&](auto v, Fault f) {
            rule.values.push_back({v[0], f});
          });
        }
        if (const toml::node* b = r.node("ranges")) {
          fault_rows(b, "fault.ranges", 2, [&](auto v, Fault f) {
            if (v[0] > v[1]) diag_.error(b, "fault.ranges", "a range's first is not past its last");
            rule.ranges.push_back({v[0], v[1], f});
          });
        }
        if (const toml::node* o = r.node("other")) rule.other = fault_at(o, "fault.other");
        if (r.node("fault") != nullptr) {
          diag_.error(r.node("fault"), "fault.fault", "a source rule names its faults per row");
        }
      }
      d_->unified.faults.push_back(std::move(rule));
    });
  }

  void continue_if_extra(TableReader& r, std::initializer_list<const char*> keys) {
    for (const char* k : keys) {
      if (const toml::node* n = r.node(k)) {
        diag_.error(n, r.qualified(k), "belongs to a source rule, not a when rule");
      }
    }
  }

  void read_simulator(TableReader& top) {
    top.read_table("simulator", false, [&](TableReader& r) {
      r.expect({"stream", "stream_ms", "nack", "tick", "on"});
      Simulated& s = d_->sim;
      if (const toml::node* n = r.node("stream")) {
        const auto* a = n->as_array();
        if (a == nullptr || !a->is_array_of_tables()) {
          diag_.error(n, "simulator.stream", "must be an array of tables ([[simulator.stream]])");
        }
        for (const auto& item : a != nullptr && a->is_array_of_tables() ? *a : toml::array{}) {
          TableReader sr(*item.as_table(), "simulator.stream", diag_);
          sr.expect({"when", "send"});
          Simulated::Stream st;
          st.when = expr(sr, "when");
          const auto m = message_ref(sr, "send", Direction::reply, true);
          if (!m) continue;
          st.send = *m;
          s.stream.push_back(std::move(st));
        }
      }
      if (auto e = expr(r, "stream_ms")) s.stream_ms = std::move(*e);
      s.nack = message_ref(r, "nack", Direction::reply, false);
      s.tick = assignments(r.node("tick"), "simulator.tick", {});
      if (const toml::node* n = r.node("on")) {
        const auto* a = n->as_array();
        if (a == nullptr || !a->is_array_of_tables()) {
          diag_.error(n, "simulator.on", "must be an array of tables ([[simulator.on]])");
          return;
        }
        for (const auto& item : *a) {
          const auto& ot = *item.as_table();
          TableReader orr(ot, "simulator.on", diag_);
          orr.expect({"request", "when", "reply", "update"});
          Simulated::Rule rule;
          const auto req = message_ref(orr, "request", Direction::request, true);
          if (!req) continue;
          rule.request = *req;
          Context ctx;
          ctx.own = &d_->messages[*req];
          rule.when = expr(orr, "when", ctx);
          rule.reply = message_ref(orr, "reply", Direction::reply, false);
          rule.update = assignments(orr.node("update"), "simulator.on.update", ctx);
          s.rules.push_back(std::move(rule));
        }
      }
    });
  }

  // ---- the rules a description must keep ---------------------------------------------------

  void check_safety(TableReader& top) {
    (void)top;
    bool motion = false;
    for (const Command c : {Command::run_forward, Command::run_reverse}) {
      const auto it = d_->commands.find(c);
      if (it == d_->commands.end()) continue;
      for (const Alternative& a : it->second) {
        if (!a.send) continue;
        motion = true;
        // What sets a motor turning is in force only once the drive showed it took it.
        if (!a.confirms) {
          diag_.error_at(a.line, "command." + std::string(to_string(c)),
                         "sends a motion command without a confirming rule: give accept (on its "
                         "reply) or until (on the device's state)");
        }
        const Message& m = d_->messages[*a.send];
        if (!a.until && m.replies.empty()) {
          diag_.error_at(a.line, "command." + std::string(to_string(c)),
                         "message '" + m.name + "' has no reply: confirm it with until");
        }
      }
    }
    if (motion && (!d_->setpoint || !d_->setpoint->limited)) {
      diag_.error_at(d_->setpoint ? d_->setpoint->line : 0, "setpoint",
                     "a description that can send a motion command needs setpoint limits (min "
                     "and max): a speed outside is refused before anything is sent");
    }
    if (motion && d_->commands.find(Command::stop) == d_->commands.end()) {
      diag_.error_at(0, "command",
                     "a description that can start the drive must say how to stop it "
                     "([[command.stop]])");
    }
    for (const auto& [c, alts] : d_->commands) {
      for (const Alternative& a : alts) {
        if (a.until && a.send && !d_->messages[*a.send].replies.empty() && !a.accept) {
          // Confirmed by state: its reply only says the frame arrived.
        }
        if (a.refuse_on && !a.until) {
          diag_.error_at(a.line, "command." + std::string(to_string(c)) + ".refuse_on",
                         "refuse_on judges the state while until waits: give until too");
        }
      }
    }
    if (d_->streaming && !d_->unified.ready) {
      diag_.error_at(0, "unified.ready", "a streaming device needs ready: when it has been heard");
    }
    for (std::size_t i = 0; i < d_->messages.size(); ++i) {
      const Message& m = d_->messages[i];
      if (m.direction == Direction::reply && !m.unsolicited && !m.nack) {
        const bool answers =
            std::any_of(d_->messages.begin(), d_->messages.end(), [&](const Message& q) {
              return std::find(q.replies.begin(), q.replies.end(), i) != q.replies.end();
            });
        if (!answers) {
          diag_.warning_at(m.line, "message." + m.name,
                           "answers no request (no replies = [...] names it) and is not "
                           "unsolicited: it will always be foreign");
        }
      }
    }
  }

  Diagnostics diag_;
  std::string source_;
  std::shared_ptr<Description> d_;
  std::set<std::string> taken_;
  std::set<std::string> option_names_;
  const toml::table* frames_ = nullptr;
  std::map<std::size_t, std::string> m_frame_;
  std::vector<const toml::table*> pending_messages_;
  std::vector<const toml::table*> pending_points_;
  std::vector<std::pair<std::size_t, const toml::table*>> pending_state_;
};

}  // namespace

std::variant<std::shared_ptr<const Description>, std::vector<std::string>> parse_description(
    std::string_view text, const std::string& source) {
  return Parser(source).run(text);
}

}  // namespace drivegate::framed
