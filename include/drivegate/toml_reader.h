// Reading TOML tables (the configuration, an adapter's own files such as the modbus adapter's
// profiles): every error names the file, the line and the key, and all errors are collected, so a
// user fixes a file in one pass. Header-only; a user links toml++ (tomlplusplus::tomlplusplus).
#pragma once

#include <toml++/toml.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <initializer_list>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

namespace drivegate {

// Collects errors with file and line; one instance per load.
class Diagnostics {
 public:
  explicit Diagnostics(std::string source) : source_(std::move(source)) {}
  void error(const toml::node* at, std::string_view key, std::string_view what) {
    const int line = at != nullptr ? static_cast<int>(at->source().begin.line) : 0;
    error_at(line, key, what);
  }
  void error_at(int line, std::string_view key, std::string_view what) {
    errors.push_back(message(line, key, what));
  }
  // Something valid but probably unwise: reported by --check-config and logged at start-up.
  void warning_at(int line, std::string_view key, std::string_view what) {
    warnings.push_back(message(line, key, what));
  }
  // From now on a key under `prefix` ("device[2]": "device[2].unit_id", "device[2].options.x")
  // is named with `name` too ("device 'pump-3'"), beside it: "device[2].unit_id (device
  // 'pump-3')". In a long file an index alone is hard to find.
  void name_table(std::string prefix, std::string name) {
    names_.emplace_back(std::move(prefix), std::move(name));
  }
  std::vector<std::string> errors;
  std::vector<std::string> warnings;

 private:
  [[nodiscard]] std::string message(int line, std::string_view key, std::string_view what) const {
    std::string msg = source_;
    if (line > 0) msg += ":" + std::to_string(line);
    msg += ": ";
    if (!key.empty()) {
      msg += key;
      for (const auto& [prefix, name] : names_) {
        const bool under =
            key.starts_with(prefix) && (key.size() == prefix.size() || key[prefix.size()] == '.');
        if (under) msg += " (" + name + ")";
      }
      msg += ": ";
    }
    msg += what;
    return msg;
  }
  std::string source_;
  std::vector<std::pair<std::string, std::string>> names_;  // key prefix, what it is called
};

// A TOML syntax error as the one who wrote the file needs it: the parser's words, and where they
// are its view of a common slip, what most likely happened. A string left open (its closing quote
// missing) runs into the end of its line, which toml++ reports as a prohibited control character
// (the line break) or, on the last line, as the end of the file.
inline std::string syntax_error_text(std::string_view text, const toml::parse_error& e) {
  std::string out(e.description());
  const std::string_view what = e.description();
  const bool in_string = what.find("string") != std::string_view::npos;
  const bool control = what.find("control characters") != std::string_view::npos;
  const bool eof = what.find("end-of-file") != std::string_view::npos;
  if (!in_string || (!control && !eof)) return out;
  // The line it stopped on, and whether it stopped at its end (columns count code points).
  const auto line_no = static_cast<std::size_t>(e.source().begin.line);
  std::size_t start = 0;
  for (std::size_t n = 1; n < line_no && start != std::string_view::npos; ++n) {
    start = text.find('\n', start);
    if (start != std::string_view::npos) ++start;
  }
  if (start == std::string_view::npos) return out;
  std::string_view line = text.substr(start, text.find('\n', start) - start);
  if (line.ends_with('\r')) line.remove_suffix(1);
  std::size_t code_points = 0;
  for (const char c : line) code_points += (static_cast<unsigned char>(c) & 0xC0) != 0x80 ? 1 : 0;
  if (!eof && static_cast<std::size_t>(e.source().begin.column) != code_points + 1) return out;
  const char quote = what.find("literal string") != std::string_view::npos ? '\'' : '"';
  return out + " (most likely a string left open: its closing " + quote + " is missing)";
}

inline int line_of(const toml::node& n) {
  return static_cast<int>(n.source().begin.line);
}

// Reads the keys of one table, refusing the unknown ones.
// A name that is also a file's name in a folder of them (a profile, a protocol description):
// 1..64 characters of a-z, 0-9, '-' and '_'.
inline bool valid_file_name(std::string_view name) {
  return !name.empty() && name.size() <= 64 && std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' || c == '_';
  });
}

// `root[key]` as an array of tables ([[key]]); nullptr when absent or (with an error) not one.
inline const toml::array* array_of_tables(const toml::table& root, std::string_view key,
                                          Diagnostics& diag) {
  const toml::node* n = root.get(key);
  if (n == nullptr) return nullptr;
  const auto* a = n->as_array();
  if (a == nullptr || !a->is_array_of_tables()) {
    diag.error(n, key, "must be an array of tables ([[" + std::string(key) + "]])");
    return nullptr;
  }
  return a;
}

class TableReader {
 public:
  TableReader(const toml::table& table, std::string prefix, Diagnostics& diag)
      : table_(table), prefix_(std::move(prefix)), diag_(diag) {}

  ~TableReader() {
    for (const auto& [key, node] : table_) {
      if (!seen_.contains(std::string(key.str()))) {
        diag_.error(&node, qualified(key.str()), "unknown key (known: " + known_list() + ")");
      }
    }
  }
  TableReader(const TableReader&) = delete;
  TableReader& operator=(const TableReader&) = delete;

  const toml::node* node(std::string_view key) {
    seen_.insert(std::string(key));
    return table_.get(key);
  }

  std::optional<std::string> string(std::string_view key, bool required) {
    const toml::node* n = node(key);
    if (n == nullptr) {
      if (required) missing(key);
      return std::nullopt;
    }
    if (const auto* s = n->as_string()) return s->get();
    diag_.error(n, qualified(key), "must be a string");
    return std::nullopt;
  }

  // A required string that is also a file's name (valid_file_name); one that is not is returned
  // too, with an error.
  std::optional<std::string> file_name(std::string_view key) {
    auto name = string(key, true);
    if (name && !valid_file_name(*name)) {
      diag_.error(node(key), qualified(key),
                  "must be 1..64 characters of a-z, 0-9, '-' and '_' (got '" + *name + "')");
    }
    return name;
  }

  std::optional<std::int64_t> integer(std::string_view key, std::int64_t min, std::int64_t max,
                                      bool required) {
    const toml::node* n = node(key);
    if (n == nullptr) {
      if (required) missing(key);
      return std::nullopt;
    }
    const auto* i = n->as_integer();
    if (i == nullptr) {
      diag_.error(n, qualified(key), "must be an integer");
      return std::nullopt;
    }
    if (i->get() < min || i->get() > max) {
      diag_.error(n, qualified(key),
                  "must be in " + std::to_string(min) + ".." + std::to_string(max) + " (got " +
                      std::to_string(i->get()) + ")");
      return std::nullopt;
    }
    return i->get();
  }

  // A number, integer or floating, within [min, max].
  std::optional<double> number(std::string_view key, double min, double max, bool required) {
    const toml::node* n = node(key);
    if (n == nullptr) {
      if (required) missing(key);
      return std::nullopt;
    }
    std::optional<double> v;
    if (const auto* i = n->as_integer()) v = static_cast<double>(i->get());
    if (const auto* f = n->as_floating_point()) v = f->get();
    if (!v) {
      diag_.error(n, qualified(key), "must be a number");
      return std::nullopt;
    }
    if (!(*v >= min && *v <= max)) {
      diag_.error(n, qualified(key),
                  "must be in " + number_text(min) + ".." + number_text(max) + " (got " +
                      number_text(*v) + ")");
      return std::nullopt;
    }
    return v;
  }

  std::optional<bool> boolean(std::string_view key) {
    const toml::node* n = node(key);
    if (n == nullptr) return std::nullopt;
    if (const auto* b = n->as_boolean()) return b->get();
    diag_.error(n, qualified(key), "must be true or false");
    return std::nullopt;
  }

  // A table at `key`; nullptr when absent (an error if `required`) or (an error) not a table.
  const toml::table* table(std::string_view key, bool required) {
    const toml::node* n = node(key);
    if (n == nullptr) {
      if (required) missing(key);
      return nullptr;
    }
    const auto* t = n->as_table();
    if (t == nullptr) diag_.error(n, qualified(key), "must be a table");
    return t;
  }

  // Each table of the array of tables at `key` ([[key]]), read by `read(r, table)`, `r` its own
  // reader as read_table() gives. False when there is none (with an error when `key` is there
  // but not an array of tables).
  template <class Read>
  bool read_each(std::string_view key, Read read) {
    node(key);
    const toml::array* a = array_of_tables(table_, key, diag_);
    if (a == nullptr) return false;
    for (const toml::node& n : *a) {
      const toml::table& t = *n.as_table();
      TableReader r(t, std::string(key), diag_);
      read(r, t);
    }
    return true;
  }

  // The table at `key`, read by `read(r)` or `read(r, table)` when it is there (as table()): `r`,
  // its own reader, names its keys `key`.KEY and reports every key `read` did not ask for once
  // `read` is done.
  template <class Read>
  void read_table(std::string_view key, bool required, Read read) {
    const toml::table* t = table(key, required);
    if (t == nullptr) return;
    TableReader r(*t, std::string(key), diag_);
    if constexpr (std::is_invocable_v<Read, TableReader&, const toml::table*>) {
      read(r, t);
    } else {
      read(r);
    }
  }

  // One of `names` at `key`: its index.
  template <std::size_t N>
  std::optional<std::size_t> choice(std::string_view key,
                                    const std::array<std::string_view, N>& names, bool required) {
    const auto text = string(key, required);
    if (!text) return std::nullopt;
    for (std::size_t i = 0; i < N; ++i) {
      if (names[i] == *text) return i;
    }
    diag_.error(node(key), qualified(key),
                "must be one of " + names_text(names) + " (got '" + *text + "')");
    return std::nullopt;
  }

  // "a, b, c": the names a key may take, for an error.
  template <std::size_t N>
  static std::string names_text(const std::array<std::string_view, N>& names) {
    std::string out;
    for (const auto n : names) out += (out.empty() ? "" : ", ") + std::string(n);
    return out;
  }

  void missing(std::string_view key) {
    diag_.error(&table_, qualified(key), "required key is missing");
  }

  [[nodiscard]] std::string qualified(std::string_view key) const {
    return prefix_.empty() ? std::string(key) : prefix_ + "." + std::string(key);
  }
  void expect(std::initializer_list<std::string_view> keys) {
    for (auto k : keys) known_.emplace_back(k);
  }

 private:
  [[nodiscard]] std::string known_list() const {
    std::string out;
    for (const auto& k : known_) out += (out.empty() ? "" : ", ") + k;
    return out;
  }
  static std::string number_text(double v) {
    std::string s = std::to_string(v);
    while (s.find('.') != std::string::npos && (s.back() == '0' || s.back() == '.')) {
      const bool dot = s.back() == '.';
      s.pop_back();
      if (dot) break;
    }
    return s;
  }

  const toml::table& table_;
  std::string prefix_;
  Diagnostics& diag_;
  std::set<std::string> seen_;
  std::vector<std::string> known_;
};

// The index of the entry named `name` in a list a file declares (a profile's points, a
// description's messages: each with a `name`); nothing when there is none.
template <class Entries>
std::optional<std::size_t> index_of(const Entries& entries, std::string_view name) {
  for (std::size_t i = 0; i < entries.size(); ++i) {
    if (entries[i].name == name) return i;
  }
  return std::nullopt;
}

}  // namespace drivegate
