// The real bus engine and real devices (gateway/device.h) on simulated time and a simulated line:
// an adapter's driver against its own simulator exactly as the daemon runs them, writes made the
// way the Modbus server makes them and registers read the way a PLC reads them, but deterministic
// and fast. Adapter tests, multi-device tests and the core's tests all run on it.
//
//   test::BusRig rig(drivegate_adapter);
//   Device& drive = rig.add_device("edrive", 1);  // the adapter's factory, default options
//   rig.add_simulator(1);
//   rig.start();
//   ASSERT_TRUE(rig.run_until([&] { return drive.online(); }, 3s));
//   EXPECT_EQ(rig.write_and_wait(drive, Table::holding, 0, {1, 3000}), Outcome::ok);
//   EXPECT_EQ(rig.sent().back(), (Bytes{0x7E, ...}));
#pragma once

#include <spdlog/logger.h>

#include <initializer_list>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "bus/bus_engine.h"
#include "config/config.h"
#include "drivegate/adapter.h"
#include "gateway/device.h"
#include "gateway/outcome.h"
#include "gateway/session.h"
#include "sim_clock.h"
#include "sim_line.h"

namespace drivegate::test {

// Adapter options as text, over the schema's defaults (parsed as `drivegate sim --set` does).
using OptionText = std::vector<std::pair<std::string, std::string>>;
Options options_of(const AdapterDescriptor& adapter, const OptionText& set = {});

// The outcome of one write: the one returned at once, or the one `done` reported.
struct WriteOutcome {
  std::optional<Outcome> result;
  [[nodiscard]] bool settled() const { return result.has_value(); }
};

class BusRig {
 public:
  // A line with the adapter's native settings (baud, parity, echo...).
  explicit BusRig(const AdapterDescriptor& adapter);
  // A line with these settings (a test of the engine with a fake adapter).
  BusRig(const AdapterDescriptor& adapter, BusConfig line);
  ~BusRig();
  BusRig(const BusRig&) = delete;
  BusRig& operator=(const BusRig&) = delete;

  // The configuration a device of this rig gets unless the test changes it.
  [[nodiscard]] DeviceConfig device_config(std::string name, std::uint32_t address,
                                           const OptionText& options = {}) const;
  // A device made by the adapter's own factory. Before start().
  Device& add_device(const DeviceConfig& config, bool maintenance = false);
  Device& add_device(std::string name, std::uint32_t address, const OptionText& options = {});
  // A device around a driver the test made (fake drivers). Before start().
  Device& add_device(const DeviceConfig& config, std::unique_ptr<Driver> driver);
  // The adapter's simulator answering at `address`. Before start().
  Simulator& add_simulator(std::uint32_t address, const OptionText& options = {});
  Simulator& add_simulator(std::unique_ptr<Simulator> sim);

  // The engine starts and the line comes up.
  void start();
  // The port fails, and comes back (a USB adapter unplugged and plugged in again).
  void line_down() { engine_->line_down(); }
  void line_up() { engine_->line_up(true); }

  void run_for(Millis span) { clock_.run_for(span); }
  bool run_until(const std::function<bool()>& done, Millis limit) {
    return clock_.run_until(done, limit);
  }
  [[nodiscard]] TimePoint now() const { return clock_.now(); }

  // A client with every right, in the register map's word order (a `maintain` listener), that
  // keeps no record of what it read (a Session without FaultReads): an onlooker.
  static inline const Session kMaintain{AccessLevel::maintain, WordOrder::big};
  // The PLC: the same rights, and like a Modbus connection it keeps what it read of the drives'
  // faults for the runs it asks. Reads and writes that name no session are its.
  [[nodiscard]] const Session& plc() const { return plc_; }

  // A Modbus write request, as the server makes it (registers, or 0 / 1 per coil).
  std::shared_ptr<WriteOutcome> write(Device& d, Table table, std::uint16_t address,
                                      std::vector<std::uint16_t> values) {
    return write(d, table, address, std::move(values), plc_);
  }
  std::shared_ptr<WriteOutcome> write(Device& d, Table table, std::uint16_t address,
                                      std::vector<std::uint16_t> values, const Session& session);
  // Runs until the write settled or `limit` passed; its outcome, nullopt if still pending.
  std::optional<Outcome> wait(const std::shared_ptr<WriteOutcome>& w, Millis limit = Millis(5000));
  std::optional<Outcome> write_and_wait(Device& d, Table table, std::uint16_t address,
                                        std::vector<std::uint16_t> values,
                                        Millis limit = Millis(5000)) {
    return write_and_wait(d, table, address, std::move(values), limit, plc_);
  }
  std::optional<Outcome> write_and_wait(Device& d, Table table, std::uint16_t address,
                                        std::vector<std::uint16_t> values, Millis limit,
                                        const Session& session);
  // Registers (or bits) as a PLC reads them, its reply in hand before it asks anything more;
  // empty when the read fails.
  std::vector<std::uint16_t> read(Device& d, Table table, std::uint16_t address, std::size_t n) {
    return read(d, table, address, n, plc_);
  }
  std::vector<std::uint16_t> read(Device& d, Table table, std::uint16_t address, std::size_t n,
                                  const Session& session);
  // The named point's registers.
  std::vector<std::uint16_t> read(Device& d, std::string_view point);
  // The named point's value as a PLC reads it: a u16 point's register, a u32 one's two high word
  // first; all ones when the read fails.
  std::uint32_t value(Device& d, std::string_view point);
  // A string point as a PLC reads it: two characters a register, the first in the high byte, cut
  // at the first NUL.
  std::string text(Device& d, std::string_view point);

  [[nodiscard]] const std::vector<SimLine::Frame>& sent() const { return line_->sent; }
  [[nodiscard]] const std::vector<SimLine::Frame>& answers() const { return line_->answers; }
  SimLine& line() { return *line_; }
  // The engine's and the devices' log: a test may add a sink to hear what they say.
  [[nodiscard]] const std::shared_ptr<spdlog::logger>& log() const { return log_; }
  SimClock& clock() { return clock_; }
  [[nodiscard]] const BusCounters& counters() const { return engine_->counters(); }
  [[nodiscard]] const std::vector<std::unique_ptr<Device>>& devices() const { return devices_; }
  Simulator& simulator(std::size_t i = 0) { return *sims_.at(i); }
  [[nodiscard]] const AdapterDescriptor& adapter() const { return adapter_; }

 private:
  const AdapterDescriptor& adapter_;
  BusConfig line_config_;
  std::shared_ptr<spdlog::logger> log_;
  SimClock clock_;
  std::unique_ptr<SimLine> line_;
  std::vector<std::unique_ptr<Device>> devices_;
  std::vector<std::unique_ptr<Simulator>> sims_;
  std::unique_ptr<BusEngine> engine_;
  Session plc_{AccessLevel::maintain, WordOrder::big, true, {}, std::make_shared<FaultReads>()};
};

}  // namespace drivegate::test
