// What the modbus adapter's tests share: a profile's text read as a test expects it (accepted, or
// refused with its errors), the request and reply PDUs of a read, and the write results a driver
// reports.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "codec.h"
#include "drivegate/driver.h"
#include "profile.h"

namespace drivegate::modbus_device::support {

// The profile in `text` (file "p.toml"); a test failure, and an empty profile, if it is refused.
inline Profile parsed(const std::string& text) {
  auto r = parse_profile(text, "p.toml");
  if (auto* errors = std::get_if<std::vector<std::string>>(&r)) {
    ADD_FAILURE() << ::testing::PrintToString(*errors);
    return {};
  }
  return std::get<Profile>(std::move(r));
}

// The errors of the profile in `text` (file "p.toml"); a test failure if it is accepted.
inline std::vector<std::string> errors_of(const std::string& text) {
  auto r = parse_profile(text, "p.toml");
  if (auto* errors = std::get_if<std::vector<std::string>>(&r)) return *errors;
  ADD_FAILURE() << "accepted:\n" << text;
  return {};
}

// `text` with `from` replaced by `to` (a profile varied for one case); a test failure if `from`
// is not in it.
inline std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

// A Write Single Register (FC 06) RTU frame to `slave`: what the slave echoes when it takes it.
inline Bytes fc06_frame(std::uint8_t slave, std::uint16_t address, std::uint16_t value) {
  std::vector<std::uint8_t> pdu = {0x06};
  put_be16(pdu, address);
  put_be16(pdu, value);
  return encode(Framing::rtu, slave, pdu);
}

// A read request PDU.
inline std::vector<std::uint8_t> read_pdu(std::uint8_t function, std::uint16_t start,
                                          std::uint16_t count) {
  std::vector<std::uint8_t> pdu = {function};
  put_be16(pdu, start);
  put_be16(pdu, count);
  return pdu;
}

// A read reply PDU carrying `words`.
inline std::vector<std::uint8_t> words_pdu(std::uint8_t function,
                                           std::vector<std::uint16_t> words) {
  std::vector<std::uint8_t> pdu = {function, static_cast<std::uint8_t>(2 * words.size())};
  for (const std::uint16_t w : words) put_be16(pdu, w);
  return pdu;
}

// The write results `d` reports, by ticket.
inline std::vector<std::pair<Ticket, WriteResult>> completions(Driver& d) {
  std::vector<Completion> done;
  d.take_completions(done);
  std::vector<std::pair<Ticket, WriteResult>> out;
  for (const Completion& c : done) out.emplace_back(c.ticket, c.result);
  return out;
}

}  // namespace drivegate::modbus_device::support
