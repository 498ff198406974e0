#include "inspect.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "codec.h"
#include "state.h"

namespace drivegate::framed {
namespace {

constexpr const char* kDirectionName[] = {"request", "reply"};
constexpr const char* kCheckKindName[] = {"xor", "sum", "sum_to", "twos_complement", "lrc", "crc"};

std::string number(double v) {
  char buf[40];
  if (std::isfinite(v) && v == std::floor(v) && std::fabs(v) < 1e15) {
    std::snprintf(buf, sizeof buf, "%.0f", v);
  } else {
    std::snprintf(buf, sizeof buf, "%.6g", v);
  }
  return buf;
}

std::string hex_number(std::uint64_t v, unsigned width) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "0x%0*llX", static_cast<int>(2 * width),
                static_cast<unsigned long long>(v));
  return buf;
}

const char* encoding_name(const Token& t) {
  switch (t.encoding) {
    case Encoding::unsigned_int:
      return "uint";
    case Encoding::signed_int:
      return "int";
    case Encoding::bcd:
      return "bcd";
    case Encoding::f32:
      return "f32";
  }
  return "uint";
}

// A Lua string literal.
std::string lua_string(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) {
      out += ' ';
      continue;
    }
    out += c;
  }
  return out + "\"";
}

}  // namespace

std::optional<Bytes> parse_hex(const std::string& text) {
  Bytes out;
  std::string digits;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == ' ' || c == '\t' || c == ',' || c == ':' || c == '\n') continue;
    if (c == '0' && i + 1 < text.size() && (text[i + 1] == 'x' || text[i + 1] == 'X')) {
      ++i;
      continue;
    }
    if (!std::isxdigit(static_cast<unsigned char>(c))) return std::nullopt;
    digits += c;
  }
  if (digits.size() % 2 != 0) return std::nullopt;
  for (std::size_t i = 0; i < digits.size(); i += 2) {
    out.push_back(static_cast<std::uint8_t>(std::stoul(digits.substr(i, 2), nullptr, 16)));
  }
  return out;
}

std::string hex_text(ByteView bytes) {
  static const char* digits = "0123456789ABCDEF";
  std::string out;
  for (const std::uint8_t b : bytes) {
    if (!out.empty()) out += ' ';
    out += digits[b >> 4];
    out += digits[b & 0xF];
  }
  return out;
}

std::string decode_text(const Description& d, ByteView bytes, std::optional<Direction> dir) {
  const Codec codec(d);
  std::ostringstream out;
  std::size_t at = 0;
  while (at < bytes.size()) {
    const ByteView rest = bytes.subspan(at);
    std::optional<Decoded<Frame>> got;
    Direction used = dir.value_or(Direction::request);
    for (const Direction each : {Direction::request, Direction::reply}) {
      if (dir && *dir != each) continue;
      const auto r = codec.decode(each, rest);
      if (!got || (got->status != DecodeStatus::frame && r.status == DecodeStatus::frame)) {
        got = r;
        used = each;
      }
      if (r.status == DecodeStatus::frame) break;
    }
    const Decoded<Frame>& r = *got;
    if (r.status == DecodeStatus::incomplete) {
      out << "incomplete: " << rest.size()
          << " bytes that may still become a frame: " << hex_text(rest) << "\n";
      break;
    }
    if (r.status == DecodeStatus::bad) {
      out << r.error.message() << ": " << r.consumed << " byte" << (r.consumed == 1 ? "" : "s")
          << " dropped: " << hex_text(rest.first(r.consumed)) << "\n";
      at += r.consumed;
      continue;
    }
    const Message& m = d.messages[r.frame.message];
    out << m.name << " (" << kDirectionName[static_cast<int>(used)] << ", " << r.consumed
        << " bytes): " << hex_text(rest.first(r.consumed)) << "\n";
    for (const Token& t : m.tokens) {
      if (t.kind == Token::Kind::field) {
        out << "  " << m.fields[t.field].name << " = " << number(codec.value(r.frame, t.field))
            << "\n";
      } else if (t.kind == Token::Kind::check) {
        std::uint64_t v = 0;
        for (std::uint8_t i = 0; i < t.width; ++i) {
          const std::uint8_t b = r.frame.bytes[t.offset + (t.little_endian ? t.width - 1 - i : i)];
          v = (v << 8) | b;
        }
        out << "  " << t.name << " = " << hex_number(v, t.width) << " (" << d.checks[t.check].name
            << ", good)\n";
      }
    }
    at += r.consumed;
  }
  return out.str();
}

std::optional<Bytes> encode_message(const Description& d, const std::string& message,
                                    const std::vector<std::pair<std::string, double>>& fields,
                                    const Options& options, std::string& error) {
  const auto index = d.message(message);
  if (!index) {
    error = "no message '" + message + "' in " + d.name + " (";
    for (std::size_t i = 0; i < d.messages.size(); ++i) {
      error += (i == 0 ? "" : ", ") + d.messages[i].name;
    }
    error += ")";
    return std::nullopt;
  }
  const Message& m = d.messages[*index];
  const State state(d, options, d.address_default);
  std::array<double, kMaxFields> values{};
  state.fill(m, {}, values);
  for (const auto& [name, value] : fields) {
    std::size_t i = 0;
    while (i < m.fields.size() && m.fields[i].name != name) ++i;
    if (i == m.fields.size()) {
      error = "message '" + message + "' has no field '" + name + "' (";
      for (std::size_t k = 0; k < m.fields.size(); ++k) {
        error += (k == 0 ? "" : ", ") + m.fields[k].name;
      }
      error += ")";
      return std::nullopt;
    }
    values[i] = value;
  }
  return Codec(d).encode(*index, {values.data(), m.fields.size()});
}

std::string lua_table(const Description& d) {
  std::ostringstream o;
  o << "-- " << d.name << ": the data adapters/framed/dissector.lua decodes it with, made by\n"
    << "-- `drivegate protocol dissector " << d.name << "` from its description: do not edit.\n"
    << "local p = {\n  name = " << lua_string(d.name) << ",\n  summary = " << lua_string(d.summary)
    << ",\n";
  const Framing& f = d.framing;
  o << "  framing = { max_frame = " << f.max_frame;
  if (f.start) o << ", start = " << int{*f.start};
  if (f.end) o << ", stop = " << int{*f.end};
  if (f.escape) o << ", escape = " << int{*f.escape} << ", escape_xor = " << int{f.escape_xor};
  o << " },\n  checks = {\n";
  for (const Check& c : d.checks) {
    o << "    { name = " << lua_string(c.name)
      << ", kind = " << lua_string(kCheckKindName[static_cast<int>(c.kind)])
      << ", width = " << int{c.width} << ", total = " << c.total << ", poly = " << c.poly
      << ", init = " << c.init << ", reflect_in = " << (c.reflect_in ? "true" : "false")
      << ", reflect_out = " << (c.reflect_out ? "true" : "false") << ", xor_out = " << c.xor_out
      << ", from = " << c.from << ", to = " << (c.to ? std::to_string(*c.to) : "nil")
      << ", step = " << int{c.step} << " },\n";
  }
  o << "  },\n  messages = {\n";
  for (const Message& m : d.messages) {
    o << "    { name = " << lua_string(m.name)
      << ", direction = " << lua_string(kDirectionName[static_cast<int>(m.direction)])
      << ", size = " << m.size << ", nack = " << (m.nack ? "true" : "false")
      << ",\n      tokens = {\n";
    for (const Token& t : m.tokens) {
      o << "        { offset = " << t.offset << ", width = " << int{t.width};
      switch (t.kind) {
        case Token::Kind::constant:
          o << ", constant = " << int{t.byte};
          break;
        case Token::Kind::field:
          o << ", field = " << lua_string(m.fields[t.field].name)
            << ", encoding = " << lua_string(encoding_name(t));
          break;
        case Token::Kind::check:
          o << ", check = " << t.check + 1 << ", name = " << lua_string(t.name);  // from 1
          break;
      }
      o << ", le = " << (t.little_endian ? "true" : "false") << " },\n";
    }
    o << "      } },\n";
  }
  o << "  },\n}\n"
    << "local drivegate = _G.drivegate or { loaded = {} }\n"
    << "_G.drivegate = drivegate\n"
    << "drivegate.framed_protocols = drivegate.framed_protocols or {}\n"
    << "if drivegate.framed_protocols[p.name] then return end\n"
    << "drivegate.framed_protocols[p.name] = p\n"
    << "if drivegate.framed_register then drivegate.framed_register(p) end\n";
  return o.str();
}

}  // namespace drivegate::framed
