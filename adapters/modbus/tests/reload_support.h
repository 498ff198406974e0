// What the reload tests share (reload_test.cpp, reload_owed_stop_test.cpp): gateways of one
// modbus device on a bus never opened (the test is the line), built and built again as a reload
// does, on a time the test sets. The bus rig runs one gateway and cannot reload; a reload here is
// the daemon's: hold_for_reload(), the held writes settle, adopt(), the old gateway's stop().
#pragma once

#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>

#include <boost/asio/io_context.hpp>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "adapter_under_test.h"
#include "bus/station.h"
#include "gateway/gateway.h"
#include "plugin/adapter_options.h"
#include "profile_support.h"

namespace drivegate::modbus_device::support {

class ReloadRig : public ::testing::Test {
 protected:
  ReloadRig(const std::string& profile, const std::string& file_name) : file_{profile, file_name} {
    plugins_.add(drivegate_adapter);
  }

  // The device `name` at `address`, of the profile under test with its default options.
  [[nodiscard]] DeviceConfig device(const std::string& name, std::uint32_t address) const {
    DeviceConfig d;
    d.name = name;
    d.bus = "a";
    d.adapter = "modbus";
    d.unit_id = 1;
    d.address = address;
    d.options = default_options(specialised_for(file_.path));
    d.options.set("profile", file_.path);
    return d;
  }
  // A configuration of that one device on bus "a", at the profile's [line] default.
  [[nodiscard]] static Config config(DeviceConfig d) {
    Config c;
    c.path = "drivegate.toml";
    BusConfig b;
    b.name = "a";
    b.port = "/nonexistent/tty-a";  // never opened
    b.baud = 19200;
    b.parity = Parity::even;
    c.buses.push_back(b);
    c.devices.push_back(std::move(d));
    return c;
  }
  std::unique_ptr<Gateway> build(const Config& c) {
    std::vector<std::string> errors;
    auto gw = Gateway::build(io_, c, plugins_, log_, errors);
    EXPECT_TRUE(errors.empty()) << errors.front();
    return gw;
  }
  // `old` replaced by `next` as the daemon's reload does, nothing held; the device `name` of next.
  Device& reload(Gateway& old, Gateway& next, const std::string& name) {
    old.hold_for_reload(next);
    next.adopt(old);
    old.stop();
    return *next.find(name);
  }
  [[nodiscard]] TimePoint at(Millis ms) const { return t0_ + ms; }
  // The status register as the PLC reads it at `at`, its reply in hand before it asks anything
  // more (gateway/fault_reads.h).
  std::uint16_t plc_reads_status(Device& d, TimePoint at) {
    std::uint16_t status = 0xFFFF;
    EXPECT_EQ(d.read(kPlc, Table::input, 0, std::span(&status, 1), at), Outcome::ok);
    kPlc.fault_reads->all_sent();
    kPlc.fault_reads->received();
    return status;
  }

  // The PLC, an operate client that keeps what it read of the drives' faults, as a Modbus
  // connection does.
  const Session kPlc{
      AccessLevel::operate, WordOrder::big, true, {}, std::make_shared<FaultReads>()};
  const ProfileFile file_;
  PluginRegistry plugins_;
  boost::asio::io_context io_;
  std::shared_ptr<spdlog::logger> log_ =
      std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::null_sink_mt>());
  const TimePoint t0_ = Clock::now();
  std::vector<Bytes> sent_;  // every frame the devices sent, in order
};

}  // namespace drivegate::modbus_device::support
