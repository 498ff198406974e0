// Several eDrives on one line ("multiple eDrives can be connected to the same RS485 network by
// use of different device ids"): two devices and two simulators on one simulated line, the
// real bus engine between them, each device made by the adapter's factory.
#include <gtest/gtest.h>

#include <algorithm>

#include "bench.h"

namespace drivegate::unicla {
namespace {

struct Pair {
  Pair() : rig(drivegate_adapter) {
    d1 = &rig.add_device("left", 1);
    d2 = &rig.add_device("right", 2);
    s1 = &rig.add_simulator(1);
    s2 = &rig.add_simulator(2);
    rig.start();
  }
  bool online() {
    return rig.run_until([&] { return d1->online() && d2->online(); }, 3s);
  }
  std::uint32_t read(Device& d, std::string_view point) { return rig.value(d, point); }
  // Frames to drive `id` with message `msg` from `from` on, and when they went out.
  std::vector<Sent> sent_to(std::uint8_t id, TimePoint from, std::optional<std::uint8_t> msg) {
    std::vector<Sent> out;
    for (auto& s : sent_by_master(rig, from)) {
      if (s.frame.destination == id && (!msg || s.frame.message_id == *msg)) out.push_back(s);
    }
    return out;
  }

  test::BusRig rig;
  Device* d1 = nullptr;
  Device* d2 = nullptr;
  Simulator* s1 = nullptr;
  Simulator* s2 = nullptr;
};

Millis max_gap(const std::vector<Sent>& frames) {
  Millis gap{0};
  for (std::size_t i = 1; i < frames.size(); ++i) {
    gap = std::max(gap, std::chrono::duration_cast<Millis>(frames[i].at - frames[i - 1].at));
  }
  return gap;
}

TEST(UniclaMultidrop, TwoDrivesOnOneLineKeepTheirOwnState) {
  Pair p;
  ASSERT_TRUE(p.online());
  // Each unit shows its own drive: serial numbers are SIM100000<id>.
  EXPECT_EQ(p.rig.text(*p.d1, "serial_number"), "SIM1000001");
  EXPECT_EQ(p.rig.text(*p.d2, "serial_number"), "SIM1000002");
  // Every frame is the master's, to drive 1 or 2; each drive's sequence numbers are its own.
  for (const auto& f : p.rig.sent()) {
    const Frame fr = decoded(f.bytes);
    EXPECT_EQ(fr.source, kMasterAddress);
    EXPECT_TRUE(fr.destination == 1 || fr.destination == 2);
  }
  const auto to1 = p.sent_to(1, {}, std::nullopt);
  const auto to2 = p.sent_to(2, {}, std::nullopt);
  ASSERT_GE(to1.size(), 3u);
  ASSERT_GE(to2.size(), 3u);
  EXPECT_EQ(to1[0].bytes, master_frame(1, kRead, kBuild, 1));
  EXPECT_EQ(to2[0].bytes, master_frame(2, kRead, kBuild, 1));
  EXPECT_EQ(p.read(*p.d1, "rs485_device_id"), 1u);
  EXPECT_EQ(p.read(*p.d2, "rs485_device_id"), 2u);

  // Right runs, left stays stopped.
  const TimePoint asked = p.rig.now();
  EXPECT_EQ(p.rig.write_and_wait(*p.d2, Table::holding, kCommandRegister, {cmd::run_forward, 3000}),
            Outcome::ok);
  const auto runs = p.rig.sent();
  for (const auto& f : runs) {
    if (f.at < asked) continue;
    const Frame fr = decoded(f.bytes);
    if (fr.command == kWrite) {
      EXPECT_EQ(fr.destination, 2);
    }
  }
  ASSERT_TRUE(p.rig.run_until([&] { return p.read(*p.d2, "speed_rpm") == 3000; }, 10s));
  EXPECT_EQ(p.read(*p.d1, "speed_rpm"), 0u);
  EXPECT_EQ(p.read(*p.d1, "status") & kRunning, 0u);
  EXPECT_EQ(p.read(*p.d1, "command"), cmd::stop);
  EXPECT_EQ(p.read(*p.d2, "command"), cmd::run_forward);

  // Left's drive loses its XC link (Fault - XC Comms): left's fault, not right's.
  p.s1->control("fault xc", p.rig.now());
  p.rig.run_for(1s);
  EXPECT_NE(p.read(*p.d1, "fault_mask") & (1u << static_cast<unsigned>(Fault::comm_lost)), 0u);
  EXPECT_NE(p.read(*p.d1, "status") & kOnline, 0u);  // the line itself is fine
  EXPECT_EQ(p.read(*p.d2, "fault_mask"), 0u);
}

TEST(UniclaMultidrop, ASilentDriveCostsTheOtherAtMostItsTimeBudget) {
  Pair p;
  ASSERT_TRUE(p.online());
  p.rig.run_for(100ms);
  const TimePoint quiet_from = p.rig.now();
  p.rig.run_for(10s);
  const auto normal = p.sent_to(1, quiet_from, kStatus);
  // Both answering: left is polled every 500 ms to the microsecond, right's reads fit between.
  EXPECT_EQ(max_gap(normal), 500ms);

  p.s2->control("silent on", p.rig.now());
  const TimePoint silent_from = p.rig.now();
  p.rig.run_for(10s);
  EXPECT_TRUE(p.d2->comm_lost());
  EXPECT_FALSE(p.d1->comm_lost());
  EXPECT_NE(p.read(*p.d1, "status") & kOnline, 0u);
  const auto with_silent = p.sent_to(1, silent_from, kStatus);
  // A silent turn of right's costs at most its attempts: 3 x (100 ms + the frame's 6 ms + the
  // 100 ms guard time after each).
  const Millis turn = 3 * 206ms;
  EXPECT_LE(max_gap(with_silent), 500ms + turn);
  EXPECT_GE(with_silent.size() + 1, normal.size() * 500 / (500 + turn.count()));
  // Right was asked again and again, three identical attempts each turn, backed off.
  const auto to_silent = p.sent_to(2, silent_from, std::nullopt);
  ASSERT_GE(to_silent.size(), 9u);
  for (std::size_t i = 0; i + 2 < to_silent.size(); i += 3) {
    EXPECT_EQ(to_silent[i].bytes, to_silent[i + 1].bytes) << i;
    EXPECT_EQ(to_silent[i + 1].bytes, to_silent[i + 2].bytes) << i;
    EXPECT_EQ(to_silent[i + 1].at - to_silent[i].at, 206ms) << i;
  }
  EXPECT_LT(to_silent.size(), with_silent.size());  // backed off: fewer than the live one's

  // Left still takes writes while its neighbour is silent.
  EXPECT_EQ(p.rig.write_and_wait(*p.d1, Table::holding, kCommandRegister, {cmd::run_forward, 3000}),
            Outcome::ok);
  EXPECT_EQ(p.read(*p.d1, "command"), cmd::run_forward);
}

}  // namespace
}  // namespace drivegate::unicla
