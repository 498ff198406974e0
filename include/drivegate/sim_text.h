// The text of simulator operator commands (the lines `drivegate sim` passes to control()) and of
// the state lines they answer with: words separated by blanks, numbers in decimal or 0x-prefixed
// hexadecimal, on / off, and registers shown in hexadecimal.
#pragma once

#include <charconv>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace drivegate {

inline std::vector<std::string> split_words(std::string_view line) {
  std::vector<std::string> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > start) out.emplace_back(line.substr(start, i - start));
  }
  return out;
}

// "42" or "0x2A", within [0, max]; nullopt for anything else.
inline std::optional<std::uint32_t> parse_unsigned(std::string_view s,
                                                   std::uint32_t max = 0xFFFFFFFFu) {
  int base = 10;
  if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
    s.remove_prefix(2);
    base = 16;
  }
  std::uint32_t v = 0;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v, base);
  if (s.empty() || ec != std::errc{} || p != s.data() + s.size() || v > max) return std::nullopt;
  return v;
}

// parse_unsigned() within the range of `T` (a byte, a register), as a `T`.
template <class T>
std::optional<T> parse_uint(std::string_view s) {
  static_assert(std::numeric_limits<T>::max() <= 0xFFFFFFFFu);
  if (const auto v = parse_unsigned(s, std::numeric_limits<T>::max())) return static_cast<T>(*v);
  return std::nullopt;
}

// "on" or "off" (a switch such as `silent on`); nullopt for anything else.
inline std::optional<bool> parse_on_off(std::string_view s) {
  if (s == "on") return true;
  if (s == "off") return false;
  return std::nullopt;
}

// An operator command line in words, and the answers simulators give alike: an error that gives
// the reason and then lists the commands, the list on `help`, and the reason an empty line gets.
class ControlLine {
 public:
  ControlLine(std::string_view line, std::string_view commands)
      : line_(line), words_(split_words(line)), commands_(commands) {}

  [[nodiscard]] const std::vector<std::string>& words() const { return words_; }
  [[nodiscard]] std::string error(const std::string& why) const {
    return "error: " + why + "; commands: " + std::string(commands_);
  }
  // The line is no command, or a command with an argument it does not take: quoted.
  [[nodiscard]] std::string unknown() const {
    return error("unknown command or bad argument '" + std::string(line_) + "'");
  }
  // The answer to an empty line or to `help`; nothing for any other line.
  [[nodiscard]] std::optional<std::string> common() const {
    if (words_.empty()) return error("empty command");
    if (words_.size() == 1 && words_[0] == "help") return "commands: " + std::string(commands_);
    return std::nullopt;
  }

 private:
  std::string_view line_;
  std::vector<std::string> words_;
  std::string_view commands_;
};

enum class HexCase : std::uint8_t { upper, lower };

// "0x" and `v` in at least `digits` hexadecimal digits, as a simulator's state line shows a
// register or a code: hex(0x2A, 4) is "0x002A".
inline std::string hex(std::uint32_t v, int digits, HexCase letters = HexCase::upper) {
  char buf[16];
  std::snprintf(buf, sizeof buf, letters == HexCase::upper ? "0x%0*X" : "0x%0*x", digits, v);
  return buf;
}

}  // namespace drivegate
