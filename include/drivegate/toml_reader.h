// Reading TOML tables (the configuration, an adapter's own files such as the modbus adapter's
// profiles): every error names the file, the line and the key, and all errors are collected, so a
// user fixes a file in one pass. Header-only; a user links toml++ (tomlplusplus::tomlplusplus).
#pragma once

#include <toml++/toml.h>

#include <initializer_list>
#include <optional>
#include <set>
#include <string>
#include <string_view>
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
  std::vector<std::string> errors;
  std::vector<std::string> warnings;

 private:
  [[nodiscard]] std::string message(int line, std::string_view key, std::string_view what) const {
    std::string msg = source_;
    if (line > 0) msg += ":" + std::to_string(line);
    msg += ": ";
    if (!key.empty()) msg += std::string(key) + ": ";
    msg += what;
    return msg;
  }
  std::string source_;
};

inline int line_of(const toml::node& n) {
  return static_cast<int>(n.source().begin.line);
}

// Reads the keys of one table, refusing the unknown ones.
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

}  // namespace drivegate
