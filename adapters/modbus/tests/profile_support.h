// What the modbus adapter's tests share: a profile's text read as a test expects it (accepted, or
// refused with its errors), with a device's options, a driver of it, the request and reply PDUs
// of a read, and the write results a driver reports.
#pragma once

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <initializer_list>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "adapter_under_test.h"
#include "codec.h"
#include "drivegate/driver.h"
#include "driver.h"
#include "example_profile.h"
#include "plugin/adapter_options.h"
#include "profile.h"
#include "profile_options.h"
#include "temp_dir.h"

namespace drivegate::modbus_device::support {

// Test profiles of more than one file (profile_options_test.cpp, required_option_test.cpp,
// reload_test.cpp vary them), profiles/<name>.toml beside this file: a line an error names is
// that file's line.

// hz-drive: a CiA 402-like drive in Hz, the reference and the output frequency in 0.01 Hz, rpm
// through the motor's poles; a run passes through "switched on" before "operation enabled".
inline const std::string kHzProfile = profile_text(DRIVEGATE_TEST_PROFILE_DIR, "hz-drive");

// pct-drive: a drive in % of its maximum, 16384 = 100 % (rpm = % x max_frequency_hz x 120 /
// motor_poles / 100).
inline const std::string kPercentProfile = profile_text(DRIVEGATE_TEST_PROFILE_DIR, "pct-drive");

// fan: an EC fan its set value runs (setpoint_rpm runs = true): holding 0 resets its errors
// (value 4), holding 1 is its set value in rpm, input 16 its actual speed, input 17 bit 4 its
// error bit (set_value_runs_test.cpp, reload_owed_stop_test.cpp).
inline const std::string kFanProfile = profile_text(DRIVEGATE_TEST_PROFILE_DIR, "fan");

// A profile's [[point]] `name` in `table` at `address`, of `type`, with the keys in `more` (five
// lines and those of `more`).
inline std::string point(const std::string& name, const std::string& table, int address,
                         const std::string& type, const std::string& more = "") {
  return "[[point]]\nname = \"" + name + "\"\ntable = \"" + table +
         "\"\naddress = " + std::to_string(address) + "\ntype = \"" + type + "\"\n" + more;
}

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

// A profile refused: the text a test's reader takes, and what each of its errors says, in order.
struct Refused {
  std::string text;
  std::vector<std::string> errors;  // each error contains the one at its place
};

// Each case's text, read by `errors_of` (which makes a profile of it), refused with as many errors
// as the case lists, each containing its own.
template <class ErrorsOf>
void expect_refused(const ErrorsOf& errors_of, std::initializer_list<Refused> cases) {
  for (const Refused& c : cases) {
    SCOPED_TRACE(c.text);
    std::vector<::testing::Matcher<std::string>> each;
    for (const std::string& e : c.errors) each.push_back(::testing::HasSubstr(e));
    EXPECT_THAT(errors_of(c.text), ::testing::ElementsAreArray(each));
  }
}

// `p` with a device's options `set` applied; a test failure if they are refused.
inline Profile with_options(Profile p, const std::vector<std::pair<std::string, double>>& set) {
  Options o;
  for (const auto& [k, v] : set) o.set(k, v);
  std::string error;
  EXPECT_TRUE(apply_options(p, o, error)) << error;
  return p;
}

// 3 attempts, comm lost after 3 s, at 19200 baud 8E1 (11 bits a character: 572.917 us).
inline constexpr Timing kTiming{3, Millis(3000), std::chrono::nanoseconds(572917)};

// The driver of `p` for `slave` on kTiming, polling every 500 ms.
inline ModbusDriver driver_of(std::uint8_t slave, Profile p) {
  return ModbusDriver(slave, std::move(p), kTiming, Millis(500));
}

// The driver of `p` for `slave` timed at the line its [line] states, as the daemon times it;
// polling every 500 ms.
inline ModbusDriver driver_at_its_line(std::uint8_t slave, Profile p) {
  const Timing t{3, Millis(3000), character_time(p.line.baud, p.line.parity, 8, p.line.stop_bits)};
  return ModbusDriver(slave, std::move(p), t, Millis(500));
}

// The frame `d` sends for a setpoint of `rpm` at `now`, or nothing when it refuses it.
inline std::optional<Bytes> setpoint_frame(ModbusDriver& d, std::int32_t rpm,
                                           TimePoint now = TimePoint{} + std::chrono::seconds(10)) {
  const WriteOp op = WriteOp::of_setpoint(rpm);
  if (d.check(std::span(&op, 1)) != WriteCheck::ok) return std::nullopt;
  if (d.apply(op, 1, now) != WriteStatus::pending) return std::nullopt;
  const auto ex = d.next_exchange(now);
  if (!ex) return std::nullopt;
  return ex->frame;
}
inline std::optional<Bytes> setpoint_frame(ModbusDriver&& d, std::int32_t rpm) {
  return setpoint_frame(d, rpm);
}

// A driver of a profile driven by hand at a time the test sets: the frame it sends next, and
// what it makes of a reply.
class DriverAtHand : public ::testing::Test {
 protected:
  DriverAtHand(std::uint8_t slave, Profile p) : d{driver_of(slave, std::move(p))} {}

  // The next frame the driver sends; none when it has nothing to send.
  Bytes sent() {
    const auto ex = d.next_exchange(now);
    return ex ? ex->frame : Bytes{};
  }

  ModbusDriver d;
  TimePoint now = TimePoint{} + std::chrono::seconds(10);
};

// A profile's text in a file of its own (`file` in a temporary directory of its own, removed
// with it), for what reads a profile by its path: the adapter's descriptor for it, the daemon.
class ProfileFile {
 public:
  explicit ProfileFile(const std::string& text, const std::string& file = "p.toml")
      : path((dir_ / file).string()) {
    std::ofstream(path) << text;
  }

 private:
  test::TempDir dir_;

 public:
  const std::string path;
};

// The adapter's descriptor for the profile at `path` (its options in the schema); a test failure,
// and the plain descriptor, if it is refused.
inline const AdapterDescriptor& specialised_for(const std::string& path) {
  Options o = default_options(drivegate_adapter);
  o.set("profile", path);
  std::string error;
  const AdapterDescriptor* a = drivegate_adapter.specialise(o, error);
  EXPECT_NE(a, nullptr) << error;
  return a != nullptr ? *a : drivegate_adapter;
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
