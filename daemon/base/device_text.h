// Text a device reports (a string point: a serial number, a drive's name) as the status JSON,
// /metrics and Sparkplug carry it: printable ASCII and line feeds as they are (each format escapes
// its own specials), every other byte '?'. A byte beyond ASCII would not be UTF-8, which all
// three require, and a control character is no text a reader could use.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace drivegate {

// The longest device text /metrics puts in a label, in characters; a longer one is cut there and
// "..." follows (a label is part of a series' name: the JSON carries the whole text).
inline constexpr std::size_t kMaxLabelText = 64;

// Appends `text` to `out`, other bytes than printable ASCII and '\n' as '?', at most `max` of
// them, then "..." when some were left out.
inline void append_device_text(std::string& out, std::string_view text,
                               std::size_t max = std::string_view::npos) {
  const std::size_t n = text.size() < max ? text.size() : max;
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    out += (c >= 0x20 && c < 0x7F) || c == '\n' ? static_cast<char>(c) : '?';
  }
  if (n < text.size()) out += "...";
}

}  // namespace drivegate
