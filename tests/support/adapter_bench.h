// One device of the adapter under test and its simulator on the real bus engine, simulated time
// and a simulated line (bus_rig.h), both made by the adapter's own factories from options as
// text, and started: what a PLC sees of one drive. Registers are read as a PLC reads them and
// written as the Modbus server writes them; the frames the master sent are kept with their times.
// Each adapter's tests add a thin layer of their own (adapters/<id>/tests/bench.h): the frames of
// its document, and what "ready" and "running" take on its protocol.
//
//   test::AdapterBench b(drivegate_adapter, {.options = {{"slave_mode", "true"}}});
//   ASSERT_TRUE(b.until_online(100ms));
//   const TimePoint asked = b.rig.now();
//   EXPECT_EQ(b.write({cmd::run_forward, 2000}), Outcome::ok);
//   EXPECT_EQ(b.frames(asked), std::vector<Bytes>{kRun2000});
#pragma once

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "bus_rig.h"
#include "common_block.h"

namespace drivegate::test {

// How the device and its simulator are made.
struct BenchSetup {
  OptionText options;                     // the device's, over the schema's defaults
  std::optional<OptionText> sim_options;  // the simulator's: the device's unless given
  std::optional<std::uint32_t> address;   // both ends': the descriptor's default unless given
  Millis poll = DeviceConfig{}.poll_interval;
  Millis budget = DeviceConfig{}.budget;
  bool maintenance = false;  // as `drivegate write` and `drivegate action` make it
};

struct AdapterBench {
  explicit AdapterBench(const AdapterDescriptor& adapter, const BenchSetup& setup = {});

  // Runs until the device is online (at most `limit`), then `idle` more, for what the protocol
  // sends right after its handshake; whether it came online.
  [[nodiscard]] bool until_online(Millis idle = Millis(0), Millis limit = Millis(3000));
  // Runs until the named point reads `value` (at most `limit`); whether it did.
  [[nodiscard]] bool until_reads(std::string_view point, std::uint32_t value, Millis limit);
  // "Run forward at `rpm`" in one request, as a PLC writes it; whether it was taken.
  [[nodiscard]] bool run_forward_at(std::uint16_t rpm);
  // A setpoint written while stopped is stored without traffic: settled as soon as it is
  // written, no frame, and setpoint_rpm reads it at once.
  testing::AssertionResult stores_without_traffic(std::uint16_t rpm);

  // From stopped: `rpm` stored without traffic, then "run forward" written goes on the line as
  // `frame` once, within `within` of the write (the line was idle: not at the next poll); it is
  // not in force until the drive confirmed it, then it is: command run_forward, running, nothing
  // pending.
  testing::AssertionResult runs_from_stopped(std::uint16_t rpm, const Bytes& frame,
                                             std::chrono::nanoseconds within);
  // A write the drive has not confirmed yet has nothing of it in force: it is not settled, `point`
  // still reads `in_force`, and the status's command-pending bit is set.
  testing::AssertionResult not_yet_in_force(const WriteOutcome& w, std::string_view point,
                                            std::uint32_t in_force);

  // Writes as the Modbus server makes them: holding registers from `address` on (the common
  // block's command unless told), waited for or left running.
  std::optional<Outcome> write(std::vector<std::uint16_t> values,
                               std::uint16_t address = common_block::kCommandRegister);
  std::shared_ptr<WriteOutcome> start_write(std::vector<std::uint16_t> values,
                                            std::uint16_t address = common_block::kCommandRegister);
  // The registers of the adapter's holding point `point`, as the PLC writes them.
  std::optional<Outcome> write(std::string_view point, std::vector<std::uint16_t> values);
  std::shared_ptr<WriteOutcome> start_write(std::string_view point,
                                            std::vector<std::uint16_t> values);
  // Engineering values to consecutive holding points from `first` on, in one request, encoded as
  // the Modbus server (or `drivegate action`) encodes them.
  std::shared_ptr<WriteOutcome> start_point_write(std::string_view first,
                                                  const std::vector<double>& values);
  std::optional<Outcome> write_point(std::string_view point, double value);
  // Where the named point starts in its table.
  [[nodiscard]] std::uint16_t address_of(std::string_view point) const;

  // Reads as a PLC reads them: a point's value (u16, or u32 high word first; all ones when the
  // read fails), as a signed 16-bit number, as a float, as text; one input register (0xFFFF when
  // the read fails), for a point whose name the common block has taken.
  std::uint32_t read(std::string_view point) { return rig.value(*drive, point); }
  std::int32_t read_i16(std::string_view point);
  float read_f32(std::string_view point);
  std::string read_text(std::string_view point) { return rig.text(*drive, point); }
  std::uint16_t input(std::uint16_t address);
  std::uint32_t status() { return read("status"); }

  // The frames the master sent, resends included: from `from` on, or after the first `mark`.
  [[nodiscard]] std::vector<Bytes> frames(TimePoint from = {}) const;
  [[nodiscard]] std::vector<Bytes> frames_after(std::size_t mark) const;
  // When `frame` went on the wire, from `from` on, and how often.
  [[nodiscard]] std::vector<TimePoint> times_of(const Bytes& frame, TimePoint from = {}) const;
  [[nodiscard]] std::size_t count(const Bytes& frame, TimePoint from = {}) const;
  [[nodiscard]] const Bytes& last() const { return rig.sent().back().bytes; }
  // The time `bytes` characters take on the adapter's line.
  [[nodiscard]] std::chrono::nanoseconds on_wire(std::size_t bytes) const;

  // An operator command to the simulator, as `drivegate sim` takes it; its answer.
  std::string control(std::string_view line) { return sim->control(line, rig.now()); }
  // Whether the simulator's `state` line holds `key_value` ("motor=on", "min=2000") as whole
  // words.
  bool sim_has(std::string_view key_value);

  BusRig rig;
  Device* drive = nullptr;
  Simulator* sim = nullptr;
};

// The fixture of an adapter's tests that begin with its drive online and the line idle: `b`, the
// adapter's own bench (adapters/<id>/tests/bench.h) made with its default setup, and
// `Bench::ready()` held before each test. A test that begins otherwise (other options, before the
// handshake) makes its own bench in a suite of its own.
//
//   using NidecWrites = test::ReadyBench<Bench>;
//   TEST_F(NidecWrites, ARunNotConfirmedIsNeverSentAfterTheFailure) {
//     b.control("silent on");
//     ...
template <class Bench>
class ReadyBench : public testing::Test {
 protected:
  void SetUp() override { ASSERT_TRUE(b.ready()); }

  Bench b;
};

}  // namespace drivegate::test
