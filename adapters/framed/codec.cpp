#include "codec.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include "drivegate/flagged.h"

namespace drivegate::framed {
namespace {

constexpr std::size_t dir_index(Direction d) {
  return d == Direction::request ? 0 : 1;
}

std::uint32_t reflect(std::uint32_t v, unsigned bits) {
  std::uint32_t r = 0;
  for (unsigned i = 0; i < bits; ++i) {
    r = (r << 1) | (v & 1u);
    v >>= 1;
  }
  return r;
}

std::uint64_t mask_of(unsigned bytes) {
  return bytes >= 8 ? ~std::uint64_t{0} : (std::uint64_t{1} << (8 * bytes)) - 1;
}

// The bytes of an integer `v` of `width` bytes in the token's order.
void put_uint(std::uint64_t v, const Token& t, std::uint8_t* at) {
  for (std::uint8_t i = 0; i < t.width; ++i) {
    const auto byte = static_cast<std::uint8_t>(v >> (8 * i));
    at[t.little_endian ? i : t.width - 1 - i] = byte;
  }
}

std::uint64_t get_uint(const Token& t, const std::uint8_t* at) {
  std::uint64_t v = 0;
  for (std::uint8_t i = 0; i < t.width; ++i) {
    const std::uint8_t byte = at[t.little_endian ? i : t.width - 1 - i];
    v |= std::uint64_t{byte} << (8 * i);
  }
  return v;
}

void write_field(const Token& t, double value, std::uint8_t* at) {
  switch (t.encoding) {
    case Encoding::f32: {
      const auto f = static_cast<float>(value);
      put_uint(std::bit_cast<std::uint32_t>(f), t, at);
      return;
    }
    case Encoding::bcd: {
      // Two digits a byte, the most significant first; clamped to what the bytes hold.
      const double top = std::pow(10.0, 2.0 * t.width) - 1;
      auto n = static_cast<std::uint64_t>(std::clamp(std::round(value), 0.0, top));
      std::uint64_t packed = 0;
      for (unsigned i = 0; i < 2u * t.width; ++i) {
        packed |= (n % 10) << (4 * i);
        n /= 10;
      }
      put_uint(packed, t, at);
      return;
    }
    case Encoding::unsigned_int:
    case Encoding::signed_int: {
      // Whole numbers, modulo the width: a signed value goes as its two's complement.
      const double r = std::isfinite(value) ? std::round(value) : 0.0;
      const auto clamped = std::clamp(r, -9.0e18, 9.0e18);
      const auto n = static_cast<std::int64_t>(clamped);
      put_uint(static_cast<std::uint64_t>(n) & mask_of(t.width), t, at);
      return;
    }
  }
}

}  // namespace

double read_field(const Token& t, ByteView frame) {
  const std::uint8_t* at = frame.data() + t.offset;
  const std::uint64_t raw = get_uint(t, at);
  switch (t.encoding) {
    case Encoding::unsigned_int:
      return static_cast<double>(raw);
    case Encoding::signed_int: {
      const std::uint64_t sign = std::uint64_t{1} << (8 * t.width - 1);
      return raw & sign ? static_cast<double>(static_cast<std::int64_t>(raw) -
                                              static_cast<std::int64_t>(sign << 1))
                        : static_cast<double>(raw);
    }
    case Encoding::bcd: {
      double v = 0;
      for (int i = 2 * t.width - 1; i >= 0; --i) {
        const auto digit = static_cast<unsigned>((raw >> (4 * i)) & 0xF);
        if (digit > 9) return std::numeric_limits<double>::quiet_NaN();  // not BCD
        v = v * 10 + digit;
      }
      return v;
    }
    case Encoding::f32:
      return static_cast<double>(std::bit_cast<float>(static_cast<std::uint32_t>(raw)));
  }
  return 0.0;
}

Codec::Codec(const Description& d) : d_(d) {
  plans_.resize(d_.messages.size());
  for (std::size_t i = 0; i < d_.messages.size(); ++i) {
    const Message& m = d_.messages[i];
    Plan& p = plans_[i];
    p.skeleton.assign(m.size, 0);
    p.fields.assign(m.fields.size(), nullptr);
    p.first_check = m.size;
    for (const Token& t : m.tokens) {
      switch (t.kind) {
        case Token::Kind::constant:
          p.skeleton[t.offset] = t.byte;
          p.constants.emplace_back(t.offset, t.byte);
          break;
        case Token::Kind::field: {
          p.fields[t.field] = &t;
          const Field& f = m.fields[t.field];
          const bool length = m.length && m.length->field == t.field;
          if (f.min || f.max || length || t.encoding == Encoding::bcd) p.judged.push_back(&t);
          break;
        }
        case Token::Kind::check:
          p.checks.push_back({.token = &t});  // the check and its range: below
          p.first_check = std::min(p.first_check, t.offset);
          break;
      }
    }
    // Every layout has a fixed size: each check's range is known now.
    p.size = m.size;
    const auto n = static_cast<long>(m.size);
    if (m.length) p.length_field = m.length->field;
    for (CheckPlan& cp : p.checks) {
      const Check& c = d_.checks[cp.token->check];
      cp.check = &c;
      const long from = std::clamp<long>(c.from >= 0 ? c.from : n + c.from, 0, n);
      long to = static_cast<long>(p.first_check);
      if (c.to) to = *c.to >= 0 ? *c.to : n + *c.to;
      cp.from = static_cast<std::size_t>(from);
      cp.to = static_cast<std::size_t>(std::clamp<long>(to, from, n));
    }
  }
  for (std::size_t i = 0; i < d_.messages.size(); ++i) {
    const Message& m = d_.messages[i];
    auto& table = by_first_[dir_index(m.direction)];
    const bool first_constant = !m.tokens.empty() && m.tokens.front().kind == Token::Kind::constant;
    for (unsigned b = 0; b < 256; ++b) {
      if (!first_constant || m.tokens.front().byte == b) table[b].all.push_back(i);
    }
  }
  // A second level where every candidate of a first byte has a constant second byte.
  for (auto& table : by_first_) {
    for (Candidates& c : table) {
      const auto second = [&](std::size_t i) -> const Token* {
        const Message& m = d_.messages[i];
        return m.tokens.size() > 1 && m.tokens[1].kind == Token::Kind::constant ? &m.tokens[1]
                                                                                : nullptr;
      };
      if (c.all.size() < 2 || !std::all_of(c.all.begin(), c.all.end(), second)) continue;
      c.by_second.resize(256);
      for (const std::size_t i : c.all) c.by_second[second(i)->byte].push_back(i);
    }
  }
  crc_tables_.resize(d_.checks.size());
  for (std::size_t c = 0; c < d_.checks.size(); ++c) {
    const Check& k = d_.checks[c];
    if (k.kind != CheckKind::crc) continue;
    const unsigned bits = 8u * k.width;
    const std::uint64_t top = std::uint64_t{1} << (bits - 1);
    const std::uint64_t mask = mask_of(k.width);
    for (unsigned b = 0; b < 256; ++b) {
      std::uint64_t r = std::uint64_t{b} << (bits - 8);
      for (int bit = 0; bit < 8; ++bit) r = (r & top) ? ((r << 1) ^ k.poly) : (r << 1);
      crc_tables_[c][b] = static_cast<std::uint32_t>(r & mask);
    }
  }
}

const std::vector<std::size_t>& Codec::candidates(Direction dir, ByteView rx) const {
  const Candidates& c = by_first_[dir_index(dir)][rx[0]];
  if (c.by_second.empty()) return c.all;
  if (rx.size() < 2) return c.all;  // not told apart yet: each waits for its second byte
  return c.by_second[rx[1]];
}

double Codec::value(const Frame& f, std::size_t field) const {
  const Token* t = plans_[f.message].fields[field];
  return read_field(*t, f.bytes);
}

void Codec::values(const Frame& f, std::span<double> out) const {
  const auto& fields = plans_[f.message].fields;
  for (std::size_t i = 0; i < fields.size() && i < out.size(); ++i) {
    out[i] = read_field(*fields[i], f.bytes);
  }
}

std::uint32_t Codec::check_value(std::size_t check, ByteView frame, std::size_t to_default) const {
  const Check& c = d_.checks[check];
  const auto n = static_cast<long>(frame.size());
  const long from = std::clamp<long>(c.from >= 0 ? c.from : n + c.from, 0, n);
  long to = static_cast<long>(to_default);
  if (c.to) to = *c.to >= 0 ? *c.to : n + *c.to;
  to = std::clamp<long>(to, from, n);
  return compute(check, frame.data(), static_cast<std::size_t>(from), static_cast<std::size_t>(to));
}

std::uint32_t Codec::compute(std::size_t check, const std::uint8_t* data, std::size_t from,
                             std::size_t to) const {
  const Check& c = d_.checks[check];
  const std::uint64_t mask = mask_of(c.width);
  std::uint64_t acc = 0;
  switch (c.kind) {
    case CheckKind::xor_bytes: {
      std::uint8_t x = 0;
      for (std::size_t i = from; i < to; i += c.step) x ^= data[i];
      return x;
    }
    case CheckKind::sum:
    case CheckKind::sum_to:
    case CheckKind::twos_complement:
    case CheckKind::lrc:
      for (std::size_t i = from; i < to; i += c.step) acc += data[i];
      if (c.kind == CheckKind::sum) return static_cast<std::uint32_t>(acc & mask);
      if (c.kind == CheckKind::sum_to) return static_cast<std::uint32_t>((c.total - acc) & mask);
      if (c.kind == CheckKind::lrc) return static_cast<std::uint32_t>((0 - (acc & 0xFF)) & 0xFF);
      return static_cast<std::uint32_t>((0 - acc) & mask);
    case CheckKind::crc: {
      const unsigned bits = 8u * c.width;
      const auto& table = crc_tables_[check];
      std::uint64_t crc = c.init & mask;
      for (std::size_t i = from; i < to; i += c.step) {
        std::uint8_t b = data[i];
        if (c.reflect_in) b = static_cast<std::uint8_t>(reflect(b, 8));
        crc = ((crc << 8) ^ table[((crc >> (bits - 8)) ^ b) & 0xFF]) & mask;
      }
      if (c.reflect_out) crc = reflect(static_cast<std::uint32_t>(crc), bits);
      return static_cast<std::uint32_t>((crc ^ c.xor_out) & mask);
    }
  }
  return 0;
}

Bytes Codec::encode(std::size_t message, std::span<const double> values) const {
  const Message& m = d_.messages.at(message);
  const Plan& p = plans_[message];
  Bytes out = p.skeleton;
  for (std::size_t i = 0; i < p.fields.size(); ++i) {
    const double v = i == p.length_field ? m.length_value : i < values.size() ? values[i] : 0.0;
    write_field(*p.fields[i], v, out.data() + p.fields[i]->offset);
  }
  for (const CheckPlan& c : p.checks) {
    put_uint(compute(c.token->check, out.data(), c.from, c.to), *c.token,
             out.data() + c.token->offset);
  }
  if (!d_.framing.flagged()) return out;
  Bytes wire;
  wire.reserve(out.size() + 8);
  wire.push_back(*d_.framing.start);
  const auto& esc = d_.framing.escaped;
  for (const std::uint8_t b : out) {
    if (d_.framing.escape && std::find(esc.begin(), esc.end(), b) != esc.end()) {
      wire.push_back(*d_.framing.escape);
      wire.push_back(static_cast<std::uint8_t>(b ^ d_.framing.escape_xor));
    } else {
      wire.push_back(b);
    }
  }
  wire.push_back(d_.framing.end.value_or(*d_.framing.start));
  return wire;
}

Codec::Fit Codec::fit(std::size_t message, ByteView rx) const {
  const Plan& p = plans_[message];
  const std::uint8_t* data = rx.data();
  if (rx.size() < p.size) {
    // The constants the bytes so far hold say no at once; all of them hold: wait for the rest.
    for (const auto& [offset, byte] : p.constants) {
      if (offset >= rx.size()) return Fit::incomplete;
      if (data[offset] != byte) return Fit::reject;
    }
    return Fit::incomplete;
  }
  for (const auto& [offset, byte] : p.constants) {
    if (data[offset] != byte) return Fit::reject;
  }
  if (!p.judged.empty()) {
    const Message& m = d_.messages[message];
    for (const Token* t : p.judged) {
      const double v = read_field(*t, rx);
      if (std::isnan(v)) return Fit::reject;
      const Field& f = m.fields[t->field];
      if ((f.min && v < *f.min) || (f.max && v > *f.max)) return Fit::reject;
      if (m.length && m.length->field == t->field && v != m.length_value) return Fit::bad_length;
    }
  }
  for (const CheckPlan& c : p.checks) {
    std::uint32_t want = 0;
    if (c.check->kind == CheckKind::xor_bytes) {  // the commonest, inline
      std::uint8_t x = 0;
      for (std::size_t i = c.from; i < c.to; i += c.check->step) x ^= data[i];
      want = x;
    } else {
      want = compute(c.token->check, data, c.from, c.to);
    }
    const std::uint32_t got =
        c.token->width == 1
            ? data[c.token->offset]
            : static_cast<std::uint32_t>(get_uint(*c.token, data + c.token->offset));
    if (got != want) return Fit::bad_check;
  }
  return Fit::good;
}

bool Codec::could_start(Direction dir, ByteView rx) const {
  if (rx.empty()) return true;
  for (const std::size_t i : candidates(dir, rx)) {
    const Fit f = fit(i, rx);
    if (f == Fit::incomplete || f == Fit::good || f == Fit::bad_check) return true;
  }
  return false;
}

Decoded<Frame> Codec::decode(Direction dir, ByteView rx) const {
  if (rx.empty()) return {};
  return d_.framing.flagged() ? decode_flagged(dir, rx) : decode_plain(dir, rx);
}

Decoded<Frame> Codec::decode_plain(Direction dir, ByteView rx) const {
  bool incomplete = false;
  bool bad_length = false;
  std::optional<std::size_t> bad_check;
  for (const std::size_t i : candidates(dir, rx)) {
    switch (fit(i, rx)) {
      case Fit::good:
        return decoded_frame(plans_[i].size, Frame{i, rx.first(plans_[i].size)});
      case Fit::incomplete:
        incomplete = true;
        break;
      case Fit::bad_check:
        if (!bad_check) bad_check = i;
        break;
      case Fit::bad_length:
        bad_length = true;
        break;
      case Fit::reject:
        break;
    }
  }
  if (incomplete) {
    // Never more than the longest frame: bytes that keep a layout waiting past it are noise.
    if (rx.size() >= d_.framing.max_frame) return decoded_bad<Frame>(1, FrameError::bad_length);
    return {};
  }
  if (bad_check) {
    // A byte may have been lost, so a good frame can start inside the damaged run: drop only up
    // to the next byte that could start one. Still a bad checksum, so the bus counts it.
    const std::size_t size = d_.messages[*bad_check].size;
    for (std::size_t k = 1; k < size; ++k) {
      if (could_start(dir, rx.subspan(k))) return decoded_bad<Frame>(k, FrameError::bad_checksum);
    }
    return decoded_bad<Frame>(size, FrameError::bad_checksum);
  }
  return decoded_bad<Frame>(1, bad_length ? FrameError::bad_length : FrameError::bad_header);
}

bool Codec::unstuff(ByteView wire, Bytes& body, FrameError& error) const {
  body.clear();
  const auto& esc = d_.framing.escaped;
  for (std::size_t i = 0; i < wire.size(); ++i) {
    if (!d_.framing.escape || wire[i] != *d_.framing.escape) {
      body.push_back(wire[i]);
      continue;
    }
    if (i + 1 >= wire.size()) {
      error = FrameError::bad_escape;
      return false;
    }
    const auto plain = static_cast<std::uint8_t>(wire[i + 1] ^ d_.framing.escape_xor);
    if (std::find(esc.begin(), esc.end(), plain) == esc.end()) {
      error = FrameError::bad_escape;
      return false;
    }
    body.push_back(plain);
    ++i;
  }
  return true;
}

Decoded<Frame> Codec::decode_flagged(Direction dir, ByteView rx) const {
  const std::uint8_t start = *d_.framing.start;
  // Past the longest frame with no end flag the start flag was not one; two flags in a row are an
  // end and the next start.
  const Decoded<std::size_t> at =
      find_flagged(rx, start, d_.framing.end.value_or(start), d_.framing.max_frame);
  if (at.status != DecodeStatus::frame) return not_a_frame<Frame>(at);
  const std::size_t end = at.frame;
  // The frame's bytes live here until the next decode on this thread (Frame::bytes).
  thread_local Bytes body;
  FrameError error = FrameError::ok;
  if (!unstuff(rx.subspan(1, end - 1), body, error)) return decoded_bad<Frame>(end, error);
  bool bad_check = false;
  for (const std::size_t i : candidates(dir, body)) {
    if (d_.messages[i].size != body.size()) continue;
    switch (fit(i, body)) {
      case Fit::good:
        return decoded_frame(end + 1, Frame{i, body});  // start flag through end flag
      case Fit::bad_check:
        bad_check = true;
        break;
      default:
        break;
    }
  }
  // The end flag stays: it may open the next frame.
  return decoded_bad<Frame>(end, bad_check ? FrameError::bad_checksum : FrameError::bad_field);
}

}  // namespace drivegate::framed
