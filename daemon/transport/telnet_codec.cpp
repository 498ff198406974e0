#include "transport/telnet_codec.h"

#include <string>

namespace drivegate::telnet {

void Decoder::feed(ByteView in, Bytes& data, std::vector<Event>& events) {
  for (const std::uint8_t b : in) {
    switch (state_) {
      case State::data:
        if (b == kIac) {
          state_ = State::iac;
        } else {
          data.push_back(b);
        }
        break;
      case State::iac:
        if (b == kIac) {  // an escaped data byte
          data.push_back(b);
          state_ = State::data;
        } else if (b == kDo || b == kDont || b == kWill || b == kWont) {
          verb_ = b;
          state_ = State::verb;
        } else if (b == kSb) {
          state_ = State::sb_option;
        } else {
          state_ = State::data;  // NOP, GA, AYT...: nothing a serial line needs
        }
        break;
      case State::verb:
        events.push_back({Event::Kind::negotiation, verb_, b, {}});
        state_ = State::data;
        break;
      case State::sb_option:
        sub_ = {Event::Kind::subnegotiation, 0, b, {}};
        state_ = State::sb_payload;
        break;
      case State::sb_payload:
        if (b == kIac) {
          state_ = State::sb_iac;
        } else if (sub_.payload.size() < kMaxPayload) {
          sub_.payload.push_back(b);
        }
        break;
      case State::sb_iac:
        if (b == kSe) {
          events.push_back(std::move(sub_));
          sub_ = {};
          state_ = State::data;
        } else {
          // IAC IAC is an escaped 0xFF in the payload; anything else is malformed and taken as
          // the same (RFC 855 leaves it undefined), so the stream stays in step.
          if (sub_.payload.size() < kMaxPayload) sub_.payload.push_back(b);
          state_ = State::sb_payload;
        }
        break;
    }
  }
}

void escape(ByteView data, Bytes& out) {
  for (const std::uint8_t b : data) {
    out.push_back(b);
    if (b == kIac) out.push_back(kIac);
  }
}

Bytes negotiation(std::uint8_t verb, std::uint8_t option) {
  return {kIac, verb, option};
}

Bytes subnegotiation(std::uint8_t option, ByteView payload) {
  Bytes out{kIac, kSb, option};
  escape(payload, out);
  out.push_back(kIac);
  out.push_back(kSe);
  return out;
}

}  // namespace drivegate::telnet

namespace drivegate::rfc2217 {

std::uint8_t parity_code(Parity p) {
  switch (p) {
    case Parity::none:
      return 1;
    case Parity::odd:
      return 2;
    case Parity::even:
      return 3;
  }
  return 1;
}

std::uint8_t stop_code(std::uint8_t stop_bits) {
  return stop_bits == 2 ? 2 : 1;
}

namespace {
Bytes command(Command c, ByteView value) {
  Bytes payload{static_cast<std::uint8_t>(c)};
  payload.insert(payload.end(), value.begin(), value.end());
  return telnet::subnegotiation(telnet::kComPortOption, payload);
}
void append(Bytes& out, const Bytes& more) {
  out.insert(out.end(), more.begin(), more.end());
}
}  // namespace

Bytes configure(const LineSettings& s) {
  Bytes out;
  const std::uint8_t baud[4] = {
      static_cast<std::uint8_t>(s.baud >> 24), static_cast<std::uint8_t>(s.baud >> 16),
      static_cast<std::uint8_t>(s.baud >> 8), static_cast<std::uint8_t>(s.baud)};
  append(out, command(Command::set_baudrate, ByteView(baud, 4)));
  const std::uint8_t size = s.data_bits;
  append(out, command(Command::set_datasize, ByteView(&size, 1)));
  const std::uint8_t parity = parity_code(s.parity);
  append(out, command(Command::set_parity, ByteView(&parity, 1)));
  const std::uint8_t stop = stop_code(s.stop_bits);
  append(out, command(Command::set_stopsize, ByteView(&stop, 1)));
  const std::uint8_t control = kNoFlowControl;
  append(out, command(Command::set_control, ByteView(&control, 1)));
  return out;
}

bool take_answer(ByteView payload, ServerSettings& s) {
  if (payload.empty()) return false;
  const int code = payload[0] - kServerReplyOffset;
  const ByteView value = payload.subspan(1);
  switch (code) {
    case static_cast<int>(Command::set_baudrate):
      if (value.size() != 4) return false;
      s.baud = (std::uint32_t{value[0]} << 24) | (std::uint32_t{value[1]} << 16) |
               (std::uint32_t{value[2]} << 8) | value[3];
      return true;
    case static_cast<int>(Command::set_datasize):
      if (value.size() != 1) return false;
      s.data_bits = value[0];
      return true;
    case static_cast<int>(Command::set_parity):
      if (value.size() != 1) return false;
      s.parity = value[0];
      return true;
    case static_cast<int>(Command::set_stopsize):
      if (value.size() != 1) return false;
      s.stop = value[0];
      return true;
    default:
      return false;
  }
}

std::string mismatch(const LineSettings& asked, const ServerSettings& got) {
  std::string out;
  const auto add = [&out](const std::string& what) { out += (out.empty() ? "" : ", ") + what; };
  if (got.baud && *got.baud != asked.baud) {
    add("baud " + std::to_string(*got.baud) + " instead of " + std::to_string(asked.baud));
  }
  if (got.data_bits && *got.data_bits != asked.data_bits) {
    add("data bits " + std::to_string(*got.data_bits) + " instead of " +
        std::to_string(asked.data_bits));
  }
  if (got.parity && *got.parity != parity_code(asked.parity)) {
    add("parity code " + std::to_string(*got.parity) + " instead of " +
        std::to_string(parity_code(asked.parity)));
  }
  if (got.stop && *got.stop != stop_code(asked.stop_bits)) {
    add("stop code " + std::to_string(*got.stop) + " instead of " +
        std::to_string(stop_code(asked.stop_bits)));
  }
  return out;
}

}  // namespace drivegate::rfc2217
