// A simulated Modbus slave from a profile: every point's registers (or bits), read and written
// with the functions a profile device is polled and written with, and a drive behind them: the
// profile's command values change the run and fault bits, the actual speed follows the reference
// while running. For `drivegate sim modbus --set profile=NAME`, the demo and the tests.
#pragma once

#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>

#include "codec.h"
#include "drivegate/simulator.h"
#include "profile.h"

namespace drivegate::modbus_device {

class ModbusSimulator final : public Simulator {
 public:
  ModbusSimulator(std::uint8_t address, Profile profile);

  Bytes on_receive(ByteView rx, TimePoint now) override;
  Bytes on_tick(TimePoint now) override;
  std::string control(std::string_view line, TimePoint now) override;

 private:
  using Key = std::pair<Table, std::uint16_t>;

  // The reply PDU to a request PDU (an exception where the slave would answer one).
  Bytes handle(ByteView pdu);
  Bytes read(Table table, ByteView pdu);
  Bytes write(ByteView pdu);
  // Whether every address of [start, start + count) of `table` is one the slave has.
  [[nodiscard]] bool holds(Table table, std::uint32_t start, std::uint32_t count) const;
  void store(Table table, std::uint16_t address, std::uint16_t word);
  void command(std::uint16_t control_word);
  void drive();  // the status word, the speed and the fault code from the drive's state
  void set_point(std::size_t point, double engineering);
  [[nodiscard]] std::optional<double> point_value(std::size_t point) const;
  [[nodiscard]] std::string state() const;

  std::uint8_t address_;
  Profile profile_;
  Bytes rx_;
  std::optional<TimePoint> last_rx_;
  std::map<Key, std::uint16_t> memory_;  // every register (or bit) of every point
  std::map<Table, std::pair<std::uint16_t, std::uint32_t>> span_;  // per table: [first, end)
  std::set<Key> missing_;                // addresses the operator removed ("missing")
  bool running_ = false;
  bool reverse_ = false;
  std::uint32_t fault_ = 0;  // native fault code; 0: none
  bool silent_ = false;
};

}  // namespace drivegate::modbus_device
