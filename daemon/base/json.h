// The one JSON string writer the output formats share (RFC 8259: quotes, backslashes and control
// characters escaped; everything else, UTF-8 included, as it is).
#pragma once

#include <string>
#include <string_view>

namespace drivegate {

// Appends `s` to `out` as a JSON string, quotes included. Most strings (names, units) need no
// escape: they go in one append.
inline void append_json_string(std::string& out, std::string_view s) {
  static constexpr char kHex[] = "0123456789abcdef";
  const auto plain = [](char ch) {
    const auto c = static_cast<unsigned char>(ch);
    return c >= 0x20 && c != '"' && c != '\\';
  };
  std::size_t i = 0;
  while (i < s.size() && plain(s[i])) ++i;
  const std::size_t at = out.size();
  out.resize(at + i + 2);
  out[at] = '"';
  s.copy(out.data() + at + 1, i);
  if (i == s.size()) {
    out.back() = '"';
    return;
  }
  out.pop_back();  // the rest, escaped
  std::size_t run = i;  // start of the pending run of plain characters
  for (; i < s.size(); ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (plain(s[i])) continue;
    out.append(s.data() + run, i - run);
    run = i + 1;
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      default: {
        const char esc[] = {'\\', 'u', '0', '0', kHex[c >> 4], kHex[c & 0xF]};
        out.append(esc, sizeof esc);
      }
    }
  }
  out.append(s.data() + run, s.size() - run);
  out += '"';
}

inline std::string json_string(std::string_view s) {
  std::string out;
  out.reserve(s.size() + 2);
  append_json_string(out, s);
  return out;
}

}  // namespace drivegate
