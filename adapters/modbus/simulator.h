// A simulated Modbus slave from a profile: every point's registers (or bits), read and written
// with the functions a profile device is polled and written with, and a drive behind them: the
// profile's command values change the run and fault bits, the actual speed follows the reference
// while running. For `drivegate sim modbus --set profile=NAME`, the demo and the tests. Its
// operator commands also make it sick the ways real slaves are: a register missing, refused a
// few times (busy), left unanswered or answered with a wrong byte count; the whole slave silent,
// late, or answering every other request; registers set raw (a float's NaN).
#pragma once

#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "codec.h"
#include "drivegate/simulator.h"
#include "profile.h"

namespace drivegate::modbus_device {

class ModbusSimulator final : public Simulator {
 public:
  ModbusSimulator(std::uint8_t address, Profile profile);

  DRIVEGATE_SIMULATOR_OVERRIDES;

 private:
  using Key = std::pair<Table, std::uint16_t>;
  // The registers (or bits) a request covers.
  struct Range {
    Table table;
    std::uint32_t start;
    std::uint32_t count;
    [[nodiscard]] bool covers(const Key& k) const {
      return k.first == table && k.second >= start && k.second < start + count;
    }
  };
  [[nodiscard]] static std::optional<Range> range_of(ByteView pdu);
  // The reply to a request PDU as the operator's commands leave it: nothing (unanswered), an
  // exception (refused, the request not carried out), a read one register short, or handle()'s.
  // A point's own write code (write_code) is served as the code it is laid out as, and answered
  // under the code asked (or, after "reply-code layout", under the code it is laid out as).
  std::optional<Bytes> answer(ByteView request);
  std::optional<Bytes> answer_laid_out(ByteView pdu);
  [[nodiscard]] std::optional<Key> key_of(std::string_view table, std::string_view address) const;

  // The reply PDU to a request PDU (an exception where the slave would answer one).
  Bytes handle(ByteView pdu);
  Bytes read(Table table, ByteView pdu);
  Bytes write(ByteView pdu);
  // Whether every address of [start, start + count) of `table` is one the slave has.
  [[nodiscard]] bool holds(Table table, std::uint32_t start, std::uint32_t count) const;
  void store(Table table, std::uint16_t address, std::uint16_t word);
  void command(Table table, std::uint16_t address, std::uint16_t word);
  void drive();  // the status word, the speed and the fault code from the drive's state
  // Runs the motor (in reverse when asked) unless the drive is faulted; false when it is.
  bool start(bool reverse);
  void set_point(std::size_t point, double engineering);
  // A point's registers as they are, and put in (nothing when `words` is none).
  [[nodiscard]] std::vector<std::uint16_t> words_of(const ProfilePoint& p) const;
  void put(const ProfilePoint& p, const std::optional<std::vector<std::uint16_t>>& words);
  [[nodiscard]] std::optional<double> point_value(std::size_t point) const;
  [[nodiscard]] std::string state() const;

  std::uint8_t address_;
  Profile profile_;
  std::vector<CodeLayout> layouts_;  // the points' own write codes (write_layouts)
  bool reply_as_layout_ = false;     // "reply-code layout": 0x41 answered as 0x06
  Bytes rx_;
  std::optional<TimePoint> last_rx_;
  std::map<Key, std::uint16_t> memory_;  // every register (or bit) of every point
  std::map<Table, std::pair<std::uint16_t, std::uint32_t>> span_;  // per table: [first, end)
  std::set<Key> missing_;  // addresses the operator removed ("missing")
  std::map<Key, std::pair<std::uint8_t, std::uint32_t>> refused_;  // exception, times left
  std::set<Key> mute_;                            // requests covering them go unanswered
  std::set<Key> short_;                           // reads covering them answer a register short
  Millis late_{0};                                // every answer this late
  std::vector<std::pair<TimePoint, Bytes>> due_;  // late answers, in order
  bool every_other_ = false;
  std::uint64_t heard_ = 0;  // requests for this slave, while every_other_
  bool running_ = false;
  bool reverse_ = false;
  // A drive its set value runs, stopped by its own stop command: still until the set value is
  // written again (setpoint_rpm runs = true with a stop bound).
  bool stopped_ = false;
  std::uint32_t fault_ = 0;  // native fault code; 0: none
  bool silent_ = false;
};

}  // namespace drivegate::modbus_device
