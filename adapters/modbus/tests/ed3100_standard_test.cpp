// The ed3100-standard profile (adapters/modbus/profiles/ed3100-standard.toml) and the ED3100's
// own adapter (adapters/ed3100/), both polling ONE simulated ED3100 on one simulated line, the
// real bus engine between them: two masters at the drive's address, each asking in turn, the
// simulator answering FC 03 in the standard form (its option sim_reply_form = standard), which
// both read. What a PLC reads from each is compared: speed, fault and running state, after runs
// and stops sent through either, and after a fault injected in the simulator.
//
// Where they differ, the difference is asserted as it is, with the reason (the profile format
// cannot say it; ed3100-standard.toml lists why):
//  - stopped, the ED3100's monitor 0x0D00 shows the frequency reference with a "stopped" bit in
//    its format word (document example: 42.28 Hz, stopped). The dedicated adapter reads 0 rpm; the
//    profile reads the reference;
//  - running in reverse, the dedicated adapter signs the speed by state bit 1; the profile cannot;
//  - native_fault with no fault: the dedicated adapter 0, the profile the raw 0xFFFF;
//  - a setpoint that is not a whole 0.01 Hz at 4 poles (not a multiple of 3 rpm): the dedicated
//    adapter rounds it, the profile refuses it (0x03).
//
// The same line also carries the last test: a dead pass-through slave beside the ED3100's own
// adapter, which must never be stalled by it.
//
// Each adapter's plugin.cpp exports `drivegate_adapter`, so this test links the two adapters'
// libraries and builds their drivers itself, as their factories do.
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>

#include "../../ed3100/driver.h"
#include "../../ed3100/settings.h"
#include "../../ed3100/simulator.h"
#include "../driver.h"
#include "../passthrough.h"
#include "../profile.h"
#include "../simulator.h"
#include "bus_rig.h"
#include "common_block.h"
#include "example_profile.h"
#include "gateway/forward_access.h"
#include "rtu_frames.h"

namespace drivegate {
namespace {

using namespace std::chrono_literals;
using namespace test::common_block;

constexpr std::uint8_t kAddress = 0x1F;  // the document's examples' drive
constexpr std::uint32_t kOther = 17;     // Fault::other

// The line both masters share, the ED3100's (9600 8E1, adapters/ed3100/plugin.cpp); the options
// are the ED3100's, for its driver's settings.
constexpr AdapterDescriptor kLine = {
    .api_version = kAdapterApiVersion,
    .id = "ed3100-line",
    .summary = "the ED3100's line, for two masters",
    .options = ed3100::kOptionSchema.data(),
    .option_count = ed3100::kOptionSchema.size(),
    .line = {.baud = 9600, .parity = Parity::even, .data_bits = 8, .stop_bits = 1, .echo = false},
    .address_min = 0,
    .address_max = 31,
    .default_address = 1,
    .streaming = false,
    .create_driver = nullptr,
    .create_simulator = nullptr,
    .demo = {},
};

modbus_device::Profile standard_profile() {
  auto r = modbus_device::parse_profile(modbus_device::shipped::text("ed3100-standard"),
                                        "ed3100-standard.toml");
  return std::get<modbus_device::Profile>(std::move(r));
}

// One ED3100 simulator and two devices at its address: "standard" (the modbus adapter with
// ed3100-standard, unit 1) and "dedicated" (the ed3100 adapter, default options, unit 2).
struct SharedDrive {
  explicit SharedDrive(ed3100::ReadForm form = ed3100::ReadForm::standard) : rig(kLine) {
    const auto char_time = character_time(9600, Parity::even, 8, 1);
    DeviceConfig s = rig.device_config("standard", kAddress);
    s.adapter = "modbus";
    s.options = {};
    auto modbus = std::make_unique<modbus_device::ModbusDriver>(
        kAddress, standard_profile(), modbus_device::Timing{3, 3000ms, char_time}, s.poll_interval);
    standard_driver = modbus.get();
    standard = &rig.add_device(s, std::move(modbus));
    DeviceConfig d = rig.device_config("dedicated", kAddress);
    d.adapter = "ed3100";
    std::string error;
    auto settings = ed3100::parse_settings(d.options, error);
    if (!settings) throw std::invalid_argument(error);
    auto own =
        std::make_unique<ed3100::Ed3100Driver>(kAddress, std::move(*settings), d.poll_interval);
    dedicated_driver = own.get();
    dedicated = &rig.add_device(d, std::move(own));
    sim = &rig.add_simulator(std::make_unique<ed3100::Ed3100Simulator>(kAddress, form));
    rig.start();
  }

  // The common block as a PLC reads it (input registers 0, 1, 4-5, 6).
  std::uint16_t status(Device& d) { return word(d, 0); }
  bool running(Device& d) { return (status(d) & kRunning) != 0; }
  bool faulted(Device& d) { return (status(d) & kFaulted) != 0; }
  std::uint16_t fault_code(Device& d) { return word(d, 1); }
  std::uint32_t native_fault(Device& d) {
    const auto r = rig.read(d, Table::input, 4, 2);
    return r.size() == 2 ? (std::uint32_t{r[0]} << 16) | r[1] : 0xFFFFFFFFu;
  }
  std::int16_t speed(Device& d) { return static_cast<std::int16_t>(word(d, 6)); }
  std::uint16_t word(Device& d, std::uint16_t address) {
    const auto r = rig.read(d, Table::input, address, 1);
    return r.empty() ? 0xFFFF : r[0];
  }

  std::optional<Outcome> write(Device& d, std::vector<std::uint16_t> values) {
    return rig.write_and_wait(d, Table::holding, kCommandRegister, std::move(values));
  }
  bool until(const std::function<bool()>& done, Millis limit = 4000ms) {
    return rig.run_until(done, limit);
  }
  // Both devices show the same running state and fault.
  testing::AssertionResult agree() {
    if (running(*standard) != running(*dedicated)) {
      return testing::AssertionFailure()
             << "running: standard " << running(*standard) << ", dedicated " << running(*dedicated);
    }
    if (faulted(*standard) != faulted(*dedicated) ||
        fault_code(*standard) != fault_code(*dedicated)) {
      return testing::AssertionFailure()
             << "fault: standard " << faulted(*standard) << "/" << fault_code(*standard)
             << ", dedicated " << faulted(*dedicated) << "/" << fault_code(*dedicated);
    }
    return testing::AssertionSuccess();
  }

  // Frames sent from `from` on.
  std::vector<Bytes> frames(std::size_t from) const {
    std::vector<Bytes> out;
    for (std::size_t i = from; i < rig.sent().size(); ++i) out.push_back(rig.sent()[i].bytes);
    return out;
  }
  bool sent_from(std::size_t from, const Bytes& frame) const {
    for (const Bytes& f : frames(from)) {
      if (f == frame) return true;
    }
    return false;
  }

  test::BusRig rig;
  Device* standard = nullptr;
  Device* dedicated = nullptr;
  Simulator* sim = nullptr;
  const Driver* standard_driver = nullptr;
  const Driver* dedicated_driver = nullptr;
};

TEST(Ed3100StandardProfile, ReadsTheSameSpeedFaultAndStateAsTheDedicatedAdapter) {
  SharedDrive b;
  ASSERT_TRUE(b.until([&] { return b.standard->online() && b.dedicated->online(); }));
  b.rig.run_for(600ms);  // a whole cycle of both

  // Stopped as the simulator starts (the document's example values: reference 42.28 Hz shown on
  // monitor 0x0D00 with the stopped bit, no fault).
  EXPECT_TRUE(b.agree());
  EXPECT_FALSE(b.running(*b.standard));
  EXPECT_EQ(b.fault_code(*b.standard), 0u);
  EXPECT_EQ(b.speed(*b.dedicated), 0);
  EXPECT_EQ(b.speed(*b.standard), 1268);  // 4228 x 0.3: the reference, shown while stopped

  // Run forward at 1500 rpm through the profile: the reference, then the command, each FC 06
  // (the dedicated adapter's codec builds the same frames).
  std::size_t mark = b.rig.sent().size();
  ASSERT_EQ(b.write(*b.standard, {cmd::run_forward, 1500}), Outcome::ok);
  EXPECT_TRUE(b.sent_from(mark, ed3100::encode_write_single(kAddress, 0x2001, 0x1388)));
  EXPECT_TRUE(b.sent_from(mark, ed3100::encode_write_single(kAddress, 0x2000, 0x001E)));
  ASSERT_TRUE(b.until([&] {
    return b.speed(*b.standard) == 1500 && b.speed(*b.dedicated) == 1500;
  }));  // the simulator ramps at 50 Hz/s
  EXPECT_TRUE(b.running(*b.standard));
  EXPECT_TRUE(b.agree());

  // Stop through the profile: the document's own stop frame. Both see the motor stop; the
  // profile's speed then reads the reference again.
  mark = b.rig.sent().size();
  ASSERT_EQ(b.write(*b.standard, {cmd::stop}), Outcome::ok);
  EXPECT_TRUE(b.sent_from(mark, Bytes{0x1F, 0x06, 0x20, 0x00, 0x00, 0x01, 0x40, 0x74}));
  ASSERT_TRUE(b.until([&] { return !b.running(*b.standard) && !b.running(*b.dedicated); }));
  b.rig.run_for(600ms);
  EXPECT_TRUE(b.agree());
  EXPECT_EQ(b.speed(*b.dedicated), 0);
  EXPECT_EQ(b.speed(*b.standard), 1500);

  // Run reverse through the dedicated adapter (FC 10: command and reference): both see it run,
  // at the same speed; only the dedicated adapter can sign it.
  ASSERT_EQ(b.write(*b.dedicated, {cmd::run_reverse, 1500}), Outcome::ok);
  ASSERT_TRUE(
      b.until([&] { return b.speed(*b.dedicated) == -1500 && b.speed(*b.standard) == 1500; }));
  EXPECT_TRUE(b.running(*b.dedicated));
  EXPECT_TRUE(b.agree());

  // A trip injected in the drive (code 7; the table is illegible: other): both show it, with the
  // same native code, and the motor stopped.
  ASSERT_EQ(b.sim->control("fault 7", b.rig.now()).rfind("ok", 0), 0u);
  ASSERT_TRUE(b.until([&] { return b.faulted(*b.standard) && b.faulted(*b.dedicated); }));
  b.rig.run_for(600ms);
  EXPECT_TRUE(b.agree());
  EXPECT_EQ(b.fault_code(*b.standard), kOther);
  EXPECT_EQ(b.native_fault(*b.standard), 7u);
  EXPECT_EQ(b.native_fault(*b.dedicated), 7u);
  EXPECT_FALSE(b.running(*b.standard));
  EXPECT_EQ(b.speed(*b.dedicated), 0);
  // A run while tripped is refused by both: by the drive (exception 04) through the profile, by
  // the dedicated adapter before the line.
  EXPECT_EQ(b.write(*b.standard, {cmd::run_forward}), Outcome::refused);
  EXPECT_EQ(b.write(*b.dedicated, {cmd::run_forward}), Outcome::refused);

  // Cleared at the drive: no fault in either. native_fault: the dedicated adapter says 0, the
  // profile the raw "no fault" word 0xFFFF.
  ASSERT_EQ(b.sim->control("clear", b.rig.now()).rfind("ok", 0), 0u);
  ASSERT_TRUE(b.until([&] { return !b.faulted(*b.standard) && !b.faulted(*b.dedicated); }));
  EXPECT_TRUE(b.agree());
  EXPECT_EQ(b.fault_code(*b.dedicated), 0u);
  EXPECT_EQ(b.native_fault(*b.dedicated), 0u);
  EXPECT_EQ(b.native_fault(*b.standard), 0xFFFFu);
}

TEST(Ed3100StandardProfile, TakesOnlySetpointsThatAreWholeHundredthsOfAHertz) {
  SharedDrive b;
  ASSERT_TRUE(b.until([&] { return b.standard->online() && b.dedicated->online(); }));
  // 1000 rpm at 4 poles is 33.333 Hz: the dedicated adapter rounds it to 0x0D05; the profile's
  // scale (0.3 rpm a count) has no whole count for it.
  EXPECT_EQ(b.rig.write_and_wait(*b.dedicated, Table::holding, kSetpointRegister, {1000}),
            Outcome::ok);
  EXPECT_EQ(b.rig.write_and_wait(*b.standard, Table::holding, kSetpointRegister, {1000}),
            Outcome::invalid_value);
  // 999 rpm is 33.30 Hz: both.
  EXPECT_EQ(b.rig.write_and_wait(*b.standard, Table::holding, kSetpointRegister, {999}),
            Outcome::ok);
  ASSERT_EQ(b.write(*b.standard, {cmd::run_forward}), Outcome::ok);
  ASSERT_TRUE(b.until([&] { return b.speed(*b.standard) == 999 && b.speed(*b.dedicated) == 999; }));
  EXPECT_TRUE(b.agree());
}

TEST(Ed3100StandardProfile, KeepsTheModbusSilenceNotTheDocuments10Ms) {
  SharedDrive b;
  // Document, "communication material structure": >= 10 ms of silence around a frame; the
  // profile cannot say so, and the adapter keeps 3.5 characters: 4.0104 ms at 9600 8E1, kept to
  // the next microsecond.
  EXPECT_EQ(b.dedicated_driver->traits().inter_frame_gap, 10ms);
  EXPECT_EQ(b.standard_driver->traits().inter_frame_gap, 4011us);
}

TEST(Ed3100StandardProfile, NeedsTheDriveToAnswerInTheStandardForm) {
  // The simulator in its default, the document's form: the dedicated adapter reads it, the
  // profile never gets a reply it can take.
  SharedDrive b(ed3100::ReadForm::document);
  EXPECT_TRUE(b.until([&] { return b.dedicated->online(); }));
  b.rig.run_for(3000ms);
  EXPECT_FALSE(b.standard->online());
}

// A pass-through window onto address `window_at` on the ED3100's line, beside the drive at
// kAddress with its dedicated adapter and its simulator (the document's read form). Nothing is
// at the window's address unless the test adds a simulator there; then it starts the rig.
struct WindowBesideTheDrive {
  explicit WindowBesideTheDrive(std::uint8_t window_at) : rig(kLine) {
    const auto char_time = character_time(9600, Parity::even, 8, 1);
    DeviceConfig w = rig.device_config("window", window_at);
    w.adapter = "modbus";
    w.options = {};
    window = &rig.add_device(
        w, std::make_unique<modbus_device::PassthroughDriver>(
               window_at, modbus_device::PassthroughSettings{}, char_time, w.poll_interval));
    DeviceConfig d = rig.device_config("dedicated", kAddress);
    d.adapter = "ed3100";
    std::string error;
    auto settings = ed3100::parse_settings(d.options, error);
    if (!settings) throw std::invalid_argument(error);
    drive = &rig.add_device(
        d, std::make_unique<ed3100::Ed3100Driver>(kAddress, std::move(*settings), d.poll_interval));
    drive_sim = &rig.add_simulator(
        std::make_unique<ed3100::Ed3100Simulator>(kAddress, ed3100::ReadForm::document));
  }

  test::BusRig rig;
  Device* window = nullptr;
  Device* drive = nullptr;
  Simulator* drive_sim = nullptr;
};

// "A dead slave is 0x0B and comm_lost without stalling another device on the same
// line (a native adapter's drive on it too)". A pass-through window onto address 20, where nobody
// answers, shares the ED3100's line with its dedicated adapter; a client keeps forwarding to the
// window for 10 s. Every request is answered 0x0B (or busy, its queue being full), the window goes
// comm_lost, and the ED3100 is polled all along: never comm_lost, its data never older than 2 s.
TEST(Ed3100StandardProfile, ADeadPassThroughSlaveNeverStallsTheNativeDriveBesideIt) {
  WindowBesideTheDrive line(20);
  test::BusRig& rig = line.rig;
  Device& window = *line.window;
  Device& drive = *line.drive;
  rig.start();
  ASSERT_TRUE(rig.run_until([&] { return drive.online(); }, 4s));

  std::size_t no_response = 0;
  std::size_t other = 0;
  std::vector<std::shared_ptr<std::optional<Outcome>>> asked;
  const TimePoint end = rig.now() + 10s;
  while (rig.now() < end) {
    auto o = std::make_shared<std::optional<Outcome>>();
    const Outcome at_once = window.forward(
        test::BusRig::kMaintain, Bytes{0x03, 0x00, 0x00, 0x00, 0x01},
        [o](Outcome r, std::span<const std::uint8_t>) { *o = r; }, rig.now());
    if (at_once != Outcome::ok) *o = at_once;
    asked.push_back(o);
    rig.run_for(20ms);
    ASSERT_FALSE(drive.comm_lost());
    ASSERT_LT(rig.value(drive, "data_age_ms"), 2000u) << "the ED3100 was starved";
  }
  rig.run_for(3s);  // the last ones settle
  for (const auto& o : asked) {
    ASSERT_TRUE(o->has_value());
    if (**o == Outcome::no_response) {
      ++no_response;
    } else if (**o != Outcome::busy) {
      ++other;
    }
  }
  EXPECT_GT(no_response, 0u);
  EXPECT_EQ(other, 0u) << "a request to a dead slave was answered as if it took it";
  EXPECT_TRUE(window.comm_lost());
}

bool holds(const Bytes& frame, const Bytes& part) {
  return std::search(frame.begin(), frame.end(), part.begin(), part.end()) != frame.end();
}

// Only whole, well-formed requests leave for the line. A read-only client sends the pass-through
// window requests that carry writes a length-parsing slave would find: the ED3100's simulator
// (which skips a function it does not know byte by byte) and the profile slave's (which ends an
// FC 03 after its 8 bytes, and an FC 08 where a CRC first holds). Each is refused at once with
// exception 03 (invalid_value), for a maintain client too, and none reaches the line: the
// ED3100 never runs, the PLC reads it stopped, and the profile slave never runs either.
TEST(PassThroughWindow, NoRequestCarriesAFrameALengthParsingSlaveWouldExecute) {
  constexpr std::uint8_t kWindow = 2;
  WindowBesideTheDrive line(kWindow);
  Simulator& slave = line.rig.add_simulator(
      std::make_unique<modbus_device::ModbusSimulator>(kWindow, modbus_device::shipped::example()));
  test::BusRig& rig = line.rig;
  rig.start();
  ASSERT_TRUE(
      rig.run_until([&] { return line.drive->online() && line.window->state().ready; }, 4s));
  // The ED3100 (document, 0x2000 / 0x2001): 40.00 Hz, then run forward; the profile slave's
  // control word (holding 0) := run_forward (0x000F).
  const Bytes speed = test::with_crc({kAddress, 0x06, 0x20, 0x01, 0x0F, 0xA0});
  const Bytes run = test::with_crc({kAddress, 0x06, 0x20, 0x00, 0x00, 0x1E});
  const Bytes slave_run = test::with_crc({kWindow, 0x06, 0x00, 0x00, 0x00, 0x0F});

  // FC 08 return query data whose data is the two writes.
  const Bytes query = test::joined({{0x08, 0x00, 0x00}, speed, run});
  // FC 03 of the status word, then the CRC a slave checks after 8 bytes, then a write behind it,
  // to the slave itself and to the ED3100.
  const Bytes read_pdu = {0x03, 0x00, 0x64, 0x00, 0x01};
  const Bytes read_frame = test::with_crc(test::joined({{kWindow}, read_pdu}));
  const Bytes trailing =
      test::joined({read_pdu, Bytes(read_frame.end() - 2, read_frame.end()), slave_run, run});
  // A frame inside a frame: FC 14 (read file record, read access) of three well-formed
  // sub-requests, whose third starts the run at the ED3100's address. The ED3100's simulator
  // skips 0x14 byte by byte, takes 8 bytes at its first 06 as a bad frame, skips on, and lands
  // on the run.
  const Bytes file = test::joined({{0x14, 0x15, 0x06, 0x00, 0x00, 0x00, 0x00, 0x00, kAddress, 0x06,
                                    0x00, 0x00, 0x00, 0x00, 0x00, kAddress},
                                   Bytes(run.begin() + 1, run.end())});
  ASSERT_EQ(file.size(), 23u);  // whole: its byte count, its sub-requests of reference type 6

  const Session read{AccessLevel::read, drivegate::WordOrder::big};
  const std::size_t mark = rig.sent().size();
  for (const Session& who : {read, test::BusRig::kMaintain}) {
    for (const Bytes& pdu : {query, trailing, file}) {
      std::optional<Outcome> outcome;
      const Outcome at_once = line.window->forward(
          who, pdu, [&](Outcome o, std::span<const std::uint8_t>) { outcome = o; }, rig.now());
      if (at_once != Outcome::ok) outcome = at_once;
      rig.run_for(500ms);
      EXPECT_EQ(outcome, Outcome::invalid_value)
          << "function " << int{pdu[0]} << ", access " << to_string(who.access);
    }
  }
  rig.run_for(2s);  // the ED3100 would ramp by now
  for (std::size_t i = mark; i < rig.sent().size(); ++i) {
    EXPECT_FALSE(holds(rig.sent()[i].bytes, run)) << "a run for the ED3100 reached the line";
    EXPECT_FALSE(holds(rig.sent()[i].bytes, slave_run)) << "a run for the slave reached the line";
  }
  EXPECT_NE(line.drive_sim->control("state", rig.now()).find(" running=0 "), std::string::npos)
      << line.drive_sim->control("state", rig.now());
  EXPECT_EQ((rig.read(*line.drive, Table::input, 0, 1).at(0) & kRunning), 0);
  EXPECT_EQ(rig.read(*line.drive, Table::holding, kCommandRegister, 1).at(0), cmd::stop);
  EXPECT_NE(slave.control("state", rig.now()).find(" stopped"), std::string::npos)
      << slave.control("state", rig.now());

  // The same functions, whole and plain, are forwarded to the read client and answered by the
  // slave: the status word, FC 08 (which the profile slave does not serve: its exception 01).
  for (const auto& [pdu, reply] :
       {std::pair{Bytes{0x03, 0x00, 0x64, 0x00, 0x01}, Bytes{0x03, 0x02}},
        std::pair{Bytes{0x08, 0x00, 0x00, 0x12, 0x34}, Bytes{0x88, 0x01}}}) {
    std::optional<Outcome> outcome;
    Bytes got;
    ASSERT_EQ(line.window->forward(
                  read, pdu,
                  [&](Outcome o, std::span<const std::uint8_t> r) {
                    outcome = o;
                    got.assign(r.begin(), r.end());
                  },
                  rig.now()),
              Outcome::ok);
    ASSERT_TRUE(rig.run_until([&] { return outcome.has_value(); }, 2s));
    EXPECT_EQ(outcome, Outcome::ok);
    EXPECT_EQ(Bytes(got.begin(), got.begin() + 2), reply);
  }
}

// The same property at large: random well-formed requests of every function the gateway knows
// the length of, half of them with an ED3100 frame (a run at its address or broadcast, or a read)
// written over some of their bytes. Every frame the gateway lets through (judge_forward), fed to
// the ED3100's simulator, leaves it as it was and answers nothing, and fed to the profile
// slave's, makes it answer exactly once: each slave takes it as one request, or as none of its
// own. Without the check, many would have moved the ED3100 (counted, to show the attacks are
// real).
TEST(PassThroughWindow, WhatItLetsThroughIsOneRequestToEveryLengthParsingSlave) {
  constexpr std::uint8_t kWindow = 2;
  const modbus_device::Profile profile = modbus_device::shipped::example();
  const std::vector<Bytes> smuggled = {
      test::with_crc({kAddress, 0x06, 0x20, 0x00, 0x00, 0x1E}),  // run forward
      test::with_crc({0x00, 0x06, 0x20, 0x00, 0x00, 0x1E}),      // the same, broadcast
      test::with_crc({kAddress, 0x03, 0x0E, 0x01, 0x00, 0x02}),  // a read
  };
  std::mt19937 rng(36);
  const auto below = [&](std::size_t n) {
    return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng);
  };
  const auto some = [&](std::size_t n) {
    Bytes b(n);
    for (auto& x : b) x = static_cast<std::uint8_t>(below(256));
    return b;
  };
  // A well-formed request PDU of `function`, its counts agreeing, its data random.
  const auto request = [&](std::uint8_t function) -> Bytes {
    Bytes pdu = {function};
    const auto add = [&](const Bytes& more) { pdu.insert(pdu.end(), more.begin(), more.end()); };
    switch (function) {
      case 0x0F: {  // N coils in ceil(N / 8) bytes
        const std::size_t bytes = 1 + below(24);
        const std::size_t n = 8 * (bytes - 1) + 1 + below(8);
        add({0x00, 0x00, static_cast<std::uint8_t>(n >> 8), static_cast<std::uint8_t>(n),
             static_cast<std::uint8_t>(bytes)});
        add(some(bytes));
        break;
      }
      case 0x10: {  // N registers in 2 x N bytes
        const std::size_t n = 1 + below(40);
        add({0x00, 0x00, 0x00, static_cast<std::uint8_t>(n), static_cast<std::uint8_t>(2 * n)});
        add(some(2 * n));
        break;
      }
      case 0x17: {
        const std::size_t n = 1 + below(40);
        add(some(4));
        add({0x00, static_cast<std::uint8_t>(n), static_cast<std::uint8_t>(2 * n)});
        add(some(2 * n));
        break;
      }
      case 0x14:
      case 0x15: {  // sub-requests of reference type 6; 0x15's with their record data
        Bytes subs;
        for (std::size_t k = 1 + below(4); k > 0; --k) {
          const std::size_t words = function == 0x15 ? below(6) : 0;
          Bytes sub = some(7);
          sub[0] = 0x06;
          if (function == 0x15) {
            sub[5] = 0x00;
            sub[6] = static_cast<std::uint8_t>(words);
          }
          subs.insert(subs.end(), sub.begin(), sub.end());
          const Bytes data = some(2 * words);
          subs.insert(subs.end(), data.begin(), data.end());
        }
        pdu.push_back(static_cast<std::uint8_t>(subs.size()));
        add(subs);
        break;
      }
      case 0x2B:
        add({0x0E});
        add(some(2));
        break;
      case 0x07:
      case 0x0B:
      case 0x0C:
      case 0x11:
        break;
      case 0x16:
        add(some(6));
        break;
      case 0x18:
        add(some(2));
        break;
      default:  // 01-06, 08: an address or sub-function and one word
        add(some(4));
        break;
    }
    return pdu;
  };
  const std::uint8_t functions[] = {0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08, 0x0B, 0x0C,
                                    0x0F, 0x10, 0x11, 0x14, 0x15, 0x16, 0x17, 0x18, 0x2B};
  const TimePoint now = TimePoint{} + 1h;
  std::size_t let_through = 0;
  std::size_t attacks_refused = 0;
  std::size_t would_have_moved = 0;
  for (int i = 0; i < 20000; ++i) {
    Bytes pdu = request(functions[below(std::size(functions))]);
    const bool attack = below(2) == 0;
    if (attack) {
      const Bytes& frame = smuggled[below(smuggled.size())];
      const std::size_t at = below(pdu.size() + frame.size());  // may overrun: appended then
      if (pdu.size() < at + frame.size()) pdu.resize(at + frame.size());
      std::copy(frame.begin(), frame.end(), pdu.begin() + static_cast<long>(at));
    }
    if (pdu.size() > modbus_serial::kMaxPdu) continue;
    const Bytes line = modbus_serial::encode(modbus_serial::Framing::rtu, kWindow, pdu);
    ed3100::Ed3100Simulator drive(kAddress, ed3100::ReadForm::document);
    const std::string before = drive.control("state", now);
    const Bytes drive_says = drive.on_receive(line, now);
    const bool moved = !drive_says.empty() || drive.control("state", now) != before;
    if (judge_forward(pdu, kWindow).refusal != Outcome::ok) {
      if (attack) ++attacks_refused;
      if (moved) ++would_have_moved;
      continue;
    }
    ++let_through;
    EXPECT_FALSE(moved) << "the ED3100 took a frame inside " << Device::describe_pdu(pdu);
    modbus_device::ModbusSimulator slave(kWindow, profile);
    const Bytes answer = slave.on_receive(line, now);
    const auto d = modbus_serial::decode_reply(modbus_serial::Framing::rtu, answer);
    ASSERT_EQ(d.status, DecodeStatus::frame) << Device::describe_pdu(pdu);
    EXPECT_EQ(d.consumed, answer.size())
        << "the slave answered more than one request in " << Device::describe_pdu(pdu);
  }
  RecordProperty("let_through", static_cast<int>(let_through));
  RecordProperty("attacks_refused", static_cast<int>(attacks_refused));
  RecordProperty("would_have_moved", static_cast<int>(would_have_moved));
  EXPECT_GT(let_through, 5000u);
  EXPECT_GT(attacks_refused, 1000u);
  EXPECT_GT(would_have_moved, 100u);
}

}  // namespace
}  // namespace drivegate
