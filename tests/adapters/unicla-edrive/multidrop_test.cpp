// Several eDrives on one line ("multiple eDrives can be connected to the same RS485 network by
// use of different device ids"): two drivers and two simulators in one process.
#include <gtest/gtest.h>

#include "codec.h"
#include "driver.h"
#include "multibus.h"
#include "points.h"
#include "simulator.h"

namespace drivegate::unicla {
namespace {

using test_support::MultiBus;

struct Pair {
  EDriveDriver d1{1, Millis(500), Settings{}};
  EDriveDriver d2{2, Millis(500), Settings{}};
  EDriveSimulator s1{1, ByteOrder::big};
  EDriveSimulator s2{2, ByteOrder::big};
  MultiBus bus{{&d1, &d2}, {&s1, &s2}};
};

std::vector<TimePoint> status_polls(const MultiBus& bus, std::size_t device, TimePoint from) {
  std::vector<TimePoint> out;
  for (const auto& s : bus.sent) {
    if (s.device != device || s.at < from) continue;
    const auto d = decode(s.frame);
    if (d.status == DecodeStatus::frame && d.frame.message_id == 0x01) out.push_back(s.at);
  }
  return out;
}

Millis max_gap(const std::vector<TimePoint>& t) {
  Millis gap{0};
  for (std::size_t i = 1; i < t.size(); ++i) {
    gap = std::max(gap, std::chrono::duration_cast<Millis>(t[i] - t[i - 1]));
  }
  return gap;
}

TEST(UniclaMultidrop, TwoDrivesOnOneLineKeepTheirOwnState) {
  Pair p;
  p.bus.run_for(Millis(1500));
  ASSERT_TRUE(p.d1.common().ready);
  ASSERT_TRUE(p.d2.common().ready);
  EXPECT_EQ(std::get<std::string>(p.d1.values()[kSerialNumber]), "SIM1000001");
  EXPECT_EQ(std::get<std::string>(p.d2.values()[kSerialNumber]), "SIM1000002");
  // Every frame of driver n is addressed to device n.
  for (const auto& s : p.bus.sent) {
    const auto d = decode(s.frame);
    ASSERT_EQ(d.status, DecodeStatus::frame);
    EXPECT_EQ(d.frame.destination, s.device + 1);
    EXPECT_EQ(d.frame.source, 0x00);
  }
  const TimePoint now = p.bus.now();
  ASSERT_EQ(p.d2.setpoint(3000, 1, now), WriteStatus::done);
  ASSERT_EQ(p.d2.command(Command::run_forward, 2, now), WriteStatus::pending);
  p.bus.run_for(Millis(5000));
  std::vector<Completion> c1, c2;
  p.d1.take_completions(c1);
  p.d2.take_completions(c2);
  EXPECT_TRUE(c1.empty());
  ASSERT_EQ(c2.size(), 1u);
  EXPECT_EQ(c2[0].result, WriteResult::ok);
  EXPECT_EQ(p.d2.common().speed_rpm, 3000);
  EXPECT_EQ(p.d1.common().speed_rpm, 0);
  EXPECT_FALSE(p.d1.common().running);

  p.s1.control("fault xc", p.bus.now());
  p.bus.run_for(Millis(1000));
  EXPECT_TRUE(p.d1.common().faults.has(Fault::comm_lost));
  EXPECT_TRUE(p.d2.common().faults.empty());
}

TEST(UniclaMultidrop, SilentDriveCostsTheOtherAtMostItsTimeoutBudget) {
  Pair p;
  p.bus.run_for(Millis(1500));
  ASSERT_TRUE(p.d1.common().ready);
  const TimePoint quiet_from = p.bus.now();
  p.bus.run_for(Millis(10000));
  const auto normal = status_polls(p.bus, 0, quiet_from);

  p.s2.control("silent on", p.bus.now());
  const TimePoint silent_from = p.bus.now() + Millis(100);
  p.bus.run_for(Millis(10000));
  const auto with_silent = status_polls(p.bus, 0, silent_from);
  EXPECT_TRUE(p.bus.comm_lost(1));
  EXPECT_FALSE(p.bus.comm_lost(0));

  // Budget of the silent drive: reply_timeout x attempts = 100 ms x 3, plus the turnaround.
  const Settings s;
  const Millis budget = s.reply_timeout * s.attempts + Millis(20);
  EXPECT_LE(max_gap(normal), Millis(500) + Millis(20));
  EXPECT_LE(max_gap(with_silent), Millis(500) + budget);
  EXPECT_GE(with_silent.size() + 1, normal.size() * 500 / (500 + budget.count()));
  // The silent drive was asked again and again, with three identical attempts each time.
  int to_silent = 0;
  for (const auto& x : p.bus.sent) to_silent += (x.device == 1 && x.at >= silent_from) ? 1 : 0;
  EXPECT_GE(to_silent, 9);
}

}  // namespace
}  // namespace drivegate::unicla
