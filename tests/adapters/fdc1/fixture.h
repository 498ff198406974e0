// Shared set-up for the fdc1 driver tests: a driver and a simulator built from the same options,
// joined by test::Loopback.
#pragma once

#include <memory>
#include <string>

#include "driver.h"
#include "loopback.h"
#include "simulator.h"

namespace drivegate::fdc1::test_support {

using OptionMap = std::map<std::string, OptionValue, std::less<>>;

inline OptionMap slave_options() {
  return {{"slave_mode", true},
          {"refresh_s", std::int64_t{30}},
          {"confirm_ms", std::int64_t{5000}},
          {"stale_ms", std::int64_t{2000}},
          {"tolerance_rpm", std::int64_t{100}},
          {"allow_nv_programming", false}};
}

struct Rig {
  explicit Rig(OptionMap options = slave_options(), bool maintenance = false) {
    DeviceEnv env;
    env.name = "fdc1";
    env.options = Options(options);
    env.maintenance = maintenance;
    std::string error;
    driver = make_driver(env, error);
    SimEnv senv;
    senv.options = Options(options);
    sim = make_simulator(senv, error);
    bus = std::make_unique<test::Loopback>(*driver, *sim);
  }
  [[nodiscard]] const CommonState& common() const { return driver->common(); }
  [[nodiscard]] const Value& value(std::size_t i) const { return driver->values().at(i); }
  [[nodiscard]] std::string state() { return sim->control("state", bus->now()); }
  [[nodiscard]] TimePoint now() const { return bus->now(); }
  bool completed(Ticket t) {
    for (const auto& c : bus->completions) {
      if (c.ticket == t) return true;
    }
    return false;
  }
  WriteResult result(Ticket t) {
    for (const auto& c : bus->completions) {
      if (c.ticket == t) return c.result;
    }
    throw std::logic_error("no completion");
  }
  // Runs until the write with ticket `t` completes (or `limit` passes).
  bool settle(Ticket t, Millis limit = Millis(20000)) {
    return bus->run_until([&] { return completed(t); }, limit);
  }
  // The controller heard, then set to `rpm` (ticket 1) and run (ticket 2) until the stream
  // confirms the run; false if it never does.
  bool run_at(std::int32_t rpm) {
    bus->run_for(Millis(600));
    driver->setpoint(rpm, 1, now());
    driver->command(Command::run_forward, 2, now());
    return settle(2);
  }

  std::unique_ptr<Driver> driver;
  std::unique_ptr<Simulator> sim;
  std::unique_ptr<test::Loopback> bus;
};

// INPUT, Programming speed (decimal 72 115 ... 85 x).
inline const Bytes kStopFrame = {0x48, 0x73, 0x00, 0x00, 0x0D, 0xAC, 0x55, 0xCF};
inline const Bytes kRun2000 = {0x48, 0x73, 0x07, 0xD0, 0x07, 0xD0, 0x55, 0x6E};
inline const Bytes kRun3000 = {0x48, 0x73, 0x0B, 0xB8, 0x0B, 0xB8, 0x55, 0x6E};

}  // namespace drivegate::fdc1::test_support
