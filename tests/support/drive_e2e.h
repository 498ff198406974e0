// The fixture of an adapter's end-to-end tests on one drive (adapters/<id>/tests/e2e_test.cpp): its
// simulator on a pseudo-terminal, the daemon with a configuration that names that line, and a PLC
// on the daemon's Modbus TCP port, connected, with the drive online before each test.
//
//   class NidecE2E : public test::DriveE2E<testing::TestWithParam<ProtocolAdapter>> {
//    protected:
//     NidecE2E() : DriveE2E("nidec-washer", "washer", {}, [](const auto& port) { ... }) {}
//   };
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "e2e.h"
#include "temp_dir.h"

namespace drivegate::test {

template <class Base = ::testing::Test>
class DriveE2E : public Base {
 protected:
  // The simulator of `adapter` (with `sim_args`) on the line linked at `line` in the test's
  // directory; the daemon (with `daemon_args`, its stderr to `log` there when given) on the
  // configuration `config` makes of that line's path.
  DriveE2E(const std::string& adapter, const std::string& line, std::vector<std::string> sim_args,
           const std::function<std::string(const std::filesystem::path&)>& config,
           std::vector<std::string> daemon_args = {}, const std::string& log = "")
      : sim_(adapter, dir_ / line, std::move(sim_args)),
        daemon_(dir_, config(dir_ / line), std::move(daemon_args),
                log.empty() ? std::filesystem::path() : dir_ / log) {}

  void SetUp() override {
    ASSERT_TRUE(plc_.connect());
    ASSERT_TRUE(comes_online(plc_)) << "never online; sim says " << state();
  }

  // What the simulator says of itself.
  std::string state() { return sim_.control("state"); }

  TempDir dir_;
  Sim sim_;
  Daemon daemon_;
  Plc plc_{daemon_.port()};
};

}  // namespace drivegate::test
