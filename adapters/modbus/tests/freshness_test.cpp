// A profile device tells the truth about how old and how sound its state is, on the real bus
// engine against the simulator (tests/support/adapter_bench.h): a block the slave refuses, leaves
// unanswered or answers with a wrong byte count is asked again and ages the data (then comm_lost),
// never leaving the last value in force under a fresh data age; a bound speed that is not a
// number is unknown (speed_rpm -32768) and a fault, by the point's own type and signedness.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "adapter_bench.h"
#include "adapter_under_test.h"
#include "common_block.h"
#include "profile_support.h"

namespace drivegate::modbus_device {
namespace {

using namespace std::chrono_literals;
using namespace test::common_block;

// The example profile's status word is holding 100, read alone (max_gap 4 keeps it apart from
// the control word and reference at holding 0..1).
constexpr std::string_view kStatusBlock = "holding 100";

std::uint32_t data_age(test::AdapterBench& b) {
  return b.read("data_age_ms");
}

bool ok(const std::string& answer) {
  return answer.rfind("ok", 0) == 0;
}

// One busy answer (exception 06) to the status word's read, then the drive trips: the status
// word is asked again at the next cycle, so the PLC reads the trip (fault bit, code, stopped)
// within a cycle or two, and the data age never passes two cycles.
TEST(ModbusFreshness, AStatusBlockRefusedOnceIsAskedAgainAndTheTripShows) {
  test::AdapterBench b(drivegate_adapter);
  ASSERT_TRUE(b.until_online());
  ASSERT_TRUE(b.run_forward_at(1000));
  ASSERT_TRUE(b.rig.run_until([&] { return (b.status() & kRunning) != 0; }, 2s));
  ASSERT_TRUE(ok(b.control(std::string("refuse ") + std::string(kStatusBlock) + " 6")));
  b.rig.run_for(600ms);                   // the refusal has been given
  ASSERT_TRUE(ok(b.control("fault 2")));  // over_current: the drive stops
  EXPECT_TRUE(
      b.rig.run_until([&] { return (b.status() & (kFaulted | kRunning)) == kFaulted; }, 1500ms))
      << "status " << b.status();
  EXPECT_EQ(b.read("fault_code"), static_cast<std::uint32_t>(Fault::over_current));
  EXPECT_LE(data_age(b), 1000u);
}

// The status word's block goes unanswered (muted), or answered with one register fewer than
// asked: the other blocks keep answering, but the state is as old as its status word, so the data
// age grows and, after the comm timeout (3 s), the device is comm_lost. Answered again, it is
// back with its status fresh.
void a_status_block_never_taken_ages_the_data(std::string_view sickness) {
  test::AdapterBench b(drivegate_adapter);
  ASSERT_TRUE(b.until_online());
  ASSERT_TRUE(b.run_forward_at(1000));
  ASSERT_TRUE(b.rig.run_until([&] { return (b.status() & kRunning) != 0; }, 2s));
  const std::string on = std::string(sickness) + " " + std::string(kStatusBlock) + " on";
  ASSERT_TRUE(ok(b.control(on)));
  const TimePoint from = b.rig.now();
  b.rig.run_for(2s);
  EXPECT_GE(data_age(b), 1500u);
  EXPECT_EQ(b.status() & kCommLost, 0u);
  ASSERT_TRUE(b.rig.run_until([&] { return (b.status() & kCommLost) != 0; }, 1500ms))
      << "data age " << data_age(b);
  EXPECT_LE(b.rig.now() - from, 3500ms);
  EXPECT_EQ(b.read("fault_code"), static_cast<std::uint32_t>(Fault::comm_lost));
  // The drive trips meanwhile; answered again, the device is back and shows it.
  ASSERT_TRUE(ok(b.control("fault 5")));
  ASSERT_TRUE(ok(b.control(std::string(sickness) + " " + std::string(kStatusBlock) + " off")));
  ASSERT_TRUE(b.rig.run_until([&] { return (b.status() & kCommLost) == 0; }, 5s));
  EXPECT_EQ(b.status() & (kFaulted | kRunning), kFaulted);
  EXPECT_EQ(b.read("fault_code"), static_cast<std::uint32_t>(Fault::drive_over_temperature));
  EXPECT_LE(data_age(b), 1000u);
}

TEST(ModbusFreshness, AStatusBlockThatTimesOutAgesTheDataUntilCommLost) {
  a_status_block_never_taken_ages_the_data("mute");
}

TEST(ModbusFreshness, AStatusBlockWithAWrongByteCountAgesTheDataUntilCommLost) {
  a_status_block_never_taken_ages_the_data("short");
}

// A device's own point whose block is refused is unknown while it is, not its last value: a
// float reads NaN; asked again, it is back.
TEST(ModbusFreshness, AnOwnPointWhoseBlockIsRefusedIsUnknownUntilReadAgain) {
  test::AdapterBench b(drivegate_adapter);
  ASSERT_TRUE(b.until_online());
  // motor_current (input 202..203, low word first) shares its block with the speed (input 200).
  ASSERT_TRUE(ok(b.control("raw input 202 0x0000 0x4148")));  // 12.5 A
  ASSERT_TRUE(b.rig.run_until([&] { return b.read_f32("motor_current") == 12.5F; }, 2s));
  ASSERT_TRUE(ok(b.control("refuse input 202 4 2")));  // slave device failure, twice
  EXPECT_TRUE(b.rig.run_until([&] { return std::isnan(b.read_f32("motor_current")); }, 2s));
  EXPECT_TRUE(b.rig.run_until([&] { return b.read_f32("motor_current") == 12.5F; }, 5s));
}

// A profile whose speed is a float, or a u32, on holding 10, and no run bit: running is then a
// speed that is not 0.
std::string speed_profile(const std::string& type) {
  return "[profile]\nname = \"speed\"\nsource = \"a test\"\n"
         "[[point]]\nname = \"status_word\"\ntable = \"holding\"\naddress = 0\n"
         "type = \"u16\"\n"
         "[[point]]\nname = \"speed\"\ntable = \"holding\"\naddress = 10\n"
         "type = \"" +
         type +
         "\"\n"
         "[common]\nspeed_rpm = \"speed\"\n";
}

struct SpeedBench {
  explicit SpeedBench(const std::string& type)
      : file(speed_profile(type), "speed.toml"),
        b(drivegate_adapter, {.options = {{"profile", file.path}}}) {}
  // The speed the PLC reads once the slave holds `high` `low` (high word first).
  std::int32_t speed_for(std::uint16_t high, std::uint16_t low) {
    const std::string words = std::to_string(high) + " " + std::to_string(low);
    EXPECT_TRUE(ok(b.control("raw holding 10 " + words)));
    b.rig.run_for(1200ms);  // two cycles
    return b.read_i16("speed_rpm");
  }
  support::ProfileFile file;
  test::AdapterBench b;
};

// The fault bit and the fault code in two reads of a cycle: a trip, or a reset, that lands between
// them. The PLC never reads the fault bit beside a code that is not the drive's (over_current, 4,
// here; never other, 17), whichever of the two is read first, and the trip shows, then clears,
// within a cycle or two.
struct Read {
  std::uint8_t function;
  std::uint16_t start;
  [[nodiscard]] bool of(const Bytes& frame) const {
    return frame.size() == 8 && frame[1] == function && frame[2] == (start >> 8) &&
           frame[3] == (start & 0xFF);
  }
};

void a_trip_or_reset_between_the_reads_never_shows_a_fault_without_its_code(test::AdapterBench& b,
                                                                            Read status,
                                                                            Read code) {
  ASSERT_TRUE(b.until_online());
  // Runs until the second of the two reads has just gone on the wire, its slave not yet asked.
  const auto between_the_reads = [&] {
    const std::size_t mark = b.rig.sent().size();
    return b.rig.run_until(
        [&] {
          int first = 0;  // 1: the status word was read first in this cycle; 2: the fault code
          for (const Bytes& f : b.frames_after(mark)) {
            const int kind = status.of(f) ? 1 : code.of(f) ? 2 : 0;
            if (kind == 0) continue;
            if (first != 0 && kind != first) return true;
            first = kind;
          }
          return false;
        },
        2s);
  };
  std::vector<std::uint32_t> codes;
  const auto faulted = [&](bool want) {
    return b.rig.run_until(
        [&] {
          const bool on = (b.status() & kFaulted) != 0;
          if (on) codes.push_back(b.read("fault_code"));
          return on == want;
        },
        1500ms);
  };
  ASSERT_TRUE(between_the_reads());
  ASSERT_TRUE(ok(b.control("fault 2")));  // over_current
  EXPECT_TRUE(faulted(true)) << "status " << b.status();
  ASSERT_TRUE(between_the_reads());
  ASSERT_TRUE(ok(b.control("fault 0")));
  EXPECT_TRUE(faulted(false)) << "status " << b.status();
  ASSERT_FALSE(codes.empty());
  for (const std::uint32_t c : codes) {
    EXPECT_EQ(c, static_cast<std::uint32_t>(Fault::over_current)) << "a fault read with code " << c;
  }
}

// The example reads its fault code (input 210) before its status word (holding 100).
TEST(ModbusFreshness, ATripOrResetBetweenTheCodeAndTheStatusWordShowsTheTripWhole) {
  test::AdapterBench b(drivegate_adapter);
  a_trip_or_reset_between_the_reads_never_shows_a_fault_without_its_code(b, {0x03, 100},
                                                                         {0x04, 210});
}

// This one reads its status word (holding 0) before its fault code (holding 20).
TEST(ModbusFreshness, ATripOrResetBetweenTheStatusWordAndTheCodeShowsTheTripWhole) {
  const support::ProfileFile file(
      "[profile]\nname = \"trip\"\nsource = \"a test\"\n[modbus]\nmax_gap = 0\n"
      "[[point]]\nname = \"status_word\"\ntable = \"holding\"\naddress = 0\ntype = \"u16\"\n"
      "[[point]]\nname = \"fault_number\"\ntable = \"holding\"\naddress = 20\ntype = \"u16\"\n"
      "[common]\nfault = { point = \"status_word\", bit = 3 }\n"
      "fault_code = { point = \"fault_number\", map = { 0 = \"none\", 2 = \"over_current\" }, "
      "other = \"other\" }\n",
      "trip.toml");
  test::AdapterBench b(drivegate_adapter, {.options = {{"profile", file.path}}});
  a_trip_or_reset_between_the_reads_never_shows_a_fault_without_its_code(b, {0x03, 0}, {0x03, 20});
}

// The fault code's block refused (exception 04) as the drive trips: the fault bit, read fresh, is
// shown within a cycle or two as a fault of kind other (its code not read), never held back until
// the code is read again.
TEST(ModbusFreshness, ATripWhileItsCodeIsRefusedShowsAsOtherWithinTwoCycles) {
  test::AdapterBench b(drivegate_adapter);
  ASSERT_TRUE(b.until_online());
  ASSERT_TRUE(ok(b.control("refuse input 210 4 20")));
  ASSERT_TRUE(ok(b.control("fault 2")));
  const TimePoint from = b.rig.now();
  ASSERT_TRUE(b.rig.run_until([&] { return (b.status() & kFaulted) != 0; }, 3s));
  EXPECT_LE(b.rig.now() - from, 1500ms);
  EXPECT_EQ(b.read("fault_code"), static_cast<std::uint32_t>(Fault::other));
}

// A comm loss forgets what was read. The drive trips anew (another kind) while silent, and once it
// answers again its fault code is refused twice. While comm_lost, fault_mask keeps the faults last
// known (device_image.cpp); once the drive is heard again, its fresh fault bit stands beside no
// code: the fault is `other`, never the kind read before the loss, until the code is read.
TEST(ModbusFreshness, AfterACommLossAFaultIsNeverShownWithTheCodeReadBeforeIt) {
  test::AdapterBench b(drivegate_adapter);
  ASSERT_TRUE(b.until_online());
  ASSERT_TRUE(ok(b.control("fault 2")));  // over_current
  const auto bit = [](Fault f) { return 1u << static_cast<unsigned>(f); };
  ASSERT_TRUE(
      b.rig.run_until([&] { return (b.read("fault_mask") & bit(Fault::over_current)) != 0; }, 2s));
  ASSERT_TRUE(ok(b.control("silent on")));
  ASSERT_TRUE(b.rig.run_until([&] { return (b.status() & kCommLost) != 0; }, 5s));
  ASSERT_TRUE(ok(b.control("fault 5")));  // drive_over_temperature
  ASSERT_TRUE(ok(b.control("refuse input 210 4 2")));
  ASSERT_TRUE(ok(b.control("silent off")));
  std::vector<std::uint32_t> masks{b.read("fault_mask")};
  const bool back = b.rig.run_until(
      [&] {
        if (b.read("fault_mask") != masks.back()) masks.push_back(b.read("fault_mask"));
        return (b.status() & kCommLost) == 0;
      },
      10s);
  ASSERT_TRUE(back);
  const std::uint32_t lost = bit(Fault::comm_lost);
  EXPECT_EQ(masks,
            (std::vector<std::uint32_t>{lost | bit(Fault::over_current), lost | bit(Fault::other),
                                        bit(Fault::drive_over_temperature)}));
  EXPECT_EQ(b.read("fault_code"), static_cast<std::uint32_t>(Fault::drive_over_temperature));
}

// The race rule of update_common keeps the kind shown when a code read after its fault bit says
// none (a reset landing between the reads); after a comm loss nothing is shown from reads, so the
// first cycle that brings the device back never keeps the kind it had before the loss. Here the
// status word (input 17) is read before the code (input 20).
TEST(ModbusFreshness, TheFirstCycleAfterACommLossKeepsNoKindFromBeforeIt) {
  const support::ProfileFile file(
      "[profile]\nname = \"order\"\nsource = \"a test\"\n[modbus]\nmax_gap = 0\n"
      "[[point]]\nname = \"status_word\"\ntable = \"input\"\naddress = 17\ntype = \"u16\"\n"
      "[[point]]\nname = \"code\"\ntable = \"input\"\naddress = 20\ntype = \"u16\"\n"
      "[common]\nfault = { point = \"status_word\", bit = 4 }\n"
      "fault_code = { point = \"code\", map = { 0 = \"none\", 2 = \"over_current\" }, "
      "other = \"other\" }\n",
      "order.toml");
  test::AdapterBench b(drivegate_adapter, {.options = {{"profile", file.path}}});
  ASSERT_TRUE(b.until_online());
  const auto bit = [](Fault f) { return 1u << static_cast<unsigned>(f); };
  ASSERT_TRUE(ok(b.control("fault 2")));
  ASSERT_TRUE(b.rig.run_until(
      [&] { return b.read("fault_code") == static_cast<std::uint32_t>(Fault::over_current); }, 2s));
  ASSERT_TRUE(ok(b.control("silent on")));
  ASSERT_TRUE(b.rig.run_until([&] { return (b.status() & kCommLost) != 0; }, 5s));
  ASSERT_TRUE(ok(b.control("fault 0")));
  ASSERT_TRUE(ok(b.control("raw input 17 16")));  // a fault bit, its code none
  ASSERT_TRUE(ok(b.control("silent off")));
  ASSERT_TRUE(b.rig.run_until(
      [&] {
        if ((b.status() & kCommLost) == 0) {
          EXPECT_EQ(b.read("fault_mask") & bit(Fault::over_current), 0u);
        }
        return (b.status() & kCommLost) == 0 &&
               b.read("fault_code") == static_cast<std::uint32_t>(Fault::other);
      },
      5s));
}

constexpr std::int32_t kUnknownSpeed = -32768;

// NaN, +-Inf and 2^32 in a float speed are no speed: speed_rpm reads the unknown mark, the status
// says a fault (sensor_fault), and the drive is never shown stopped at 0 rpm.
TEST(ModbusFreshness, AFloatSpeedThatIsNotANumberIsUnknownAndAFault) {
  SpeedBench s("f32");
  ASSERT_TRUE(s.b.until_online());
  EXPECT_EQ(s.speed_for(0x447A, 0x0000), 1000);  // 1000.0
  EXPECT_EQ(s.b.status() & kFaulted, 0u);
  for (const auto& [high, low] : {std::pair{0x7FC0, 0x0000},     // NaN
                                  std::pair{0x7F80, 0x0000},     // +Inf
                                  std::pair{0xFF80, 0x0000},     // -Inf
                                  std::pair{0x4F80, 0x0000}}) {  // 2^32
    SCOPED_TRACE(testing::Message() << std::hex << high << " " << low);
    EXPECT_EQ(s.speed_for(static_cast<std::uint16_t>(high), static_cast<std::uint16_t>(low)),
              kUnknownSpeed);
    EXPECT_NE(s.b.status() & kFaulted, 0u);
    EXPECT_NE(s.b.status() & kRunning, 0u) << "no run bit set, but a speed nobody knows";
    EXPECT_EQ(s.b.read("fault_code"), static_cast<std::uint32_t>(Fault::sensor_fault));
  }
  EXPECT_EQ(s.speed_for(0xC47A, 0x0000), -1000);  // -1000.0: a number again, no fault
  EXPECT_EQ(s.b.status() & kFaulted, 0u);
}

// A u32 speed is unsigned: 0xFFFFFFFF is 4294967295 rpm, beyond what speed_rpm carries
// (unknown), never -1 (reverse).
TEST(ModbusFreshness, AU32SpeedKeepsItsSignedness) {
  SpeedBench s("u32");
  ASSERT_TRUE(s.b.until_online());
  EXPECT_EQ(s.speed_for(0x0000, 0x0064), 100);
  EXPECT_EQ(s.speed_for(0xFFFF, 0xFFFF), kUnknownSpeed);
  EXPECT_NE(s.b.status() & kFaulted, 0u);
  EXPECT_EQ(s.speed_for(0x0000, 0x7FFF), 32767);  // the largest speed carried
  EXPECT_EQ(s.speed_for(0x0000, 0x8000), kUnknownSpeed);
}

}  // namespace
}  // namespace drivegate::modbus_device
