// Shared set-up for the driver tests: one eDrive driver against its simulator on a Loopback.
#pragma once

#include <gtest/gtest.h>

#include <optional>

#include "codec.h"
#include "driver.h"
#include "loopback.h"
#include "simulator.h"

namespace drivegate::unicla::test_support {

inline Frame sent_frame(const Bytes& wire) {
  const auto d = decode(wire);
  EXPECT_EQ(d.status, DecodeStatus::frame);
  EXPECT_EQ(d.consumed, wire.size());
  return d.frame;
}

struct Rig {
  explicit Rig(std::uint8_t address = 1, Settings s = {}, ByteOrder sim_order = ByteOrder::big)
      : driver(address, Millis(500), s), sim(address, sim_order), bus(driver, sim) {}

  // Runs until the start-up reads are done and one status is in.
  void start() {
    ASSERT_TRUE(bus.run_until([&] { return driver.common().ready; }, Millis(3000)));
    bus.run_for(Millis(100));
  }

  // Runs until the ticket completes; returns its result.
  std::optional<WriteResult> wait(Ticket t, Millis limit = Millis(5000)) {
    std::optional<WriteResult> r;
    bus.run_until(
        [&] {
          for (const Completion& c : bus.completions) {
            if (c.ticket == t) r = c.result;
          }
          return r.has_value();
        },
        limit);
    return r;
  }

  // Started (start()), then set to `rpm` (ticket 1) and run (ticket 2); returns the run's result.
  std::optional<WriteResult> run_at(std::int32_t rpm) {
    start();
    driver.setpoint(rpm, 1, now());
    driver.command(Command::run_forward, 2, now());
    return wait(2);
  }

  // Frames sent since index `from` with this message id.
  std::vector<Frame> sent_with(std::uint8_t id, std::size_t from = 0) const {
    std::vector<Frame> out;
    for (std::size_t i = from; i < bus.sent.size(); ++i) {
      Frame f = sent_frame(bus.sent[i]);
      if (f.message_id == id) out.push_back(f);
    }
    return out;
  }

  TimePoint now() const { return bus.now(); }

  EDriveDriver driver;
  EDriveSimulator sim;
  test::Loopback bus;
};

}  // namespace drivegate::unicla::test_support
