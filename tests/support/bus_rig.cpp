#include "bus_rig.h"

#include <spdlog/sinks/null_sink.h>
#include <spdlog/sinks/stdout_sinks.h>

#include <cstdlib>
#include <stdexcept>

#include "gateway/gateway.h"
#include "plugin/adapter_options.h"

namespace drivegate::test {

namespace {

// DRIVEGATE_TEST_LOG=trace (or debug, info) shows the engine's and devices' log on stderr.
std::shared_ptr<spdlog::logger> test_logger() {
  const char* level = std::getenv("DRIVEGATE_TEST_LOG");
  if (level == nullptr) {
    return std::make_shared<spdlog::logger>("test",
                                            std::make_shared<spdlog::sinks::null_sink_mt>());
  }
  auto log =
      std::make_shared<spdlog::logger>("test", std::make_shared<spdlog::sinks::stderr_sink_mt>());
  log->set_level(spdlog::level::from_str(level));
  return log;
}

BusConfig native_line(const AdapterDescriptor& a) {
  BusConfig b;
  b.name = a.id;
  b.port = "simulated";
  b.baud = a.line.baud;
  b.parity = a.line.parity;
  b.data_bits = a.line.data_bits;
  b.stop_bits = a.line.stop_bits;
  b.echo = a.line.echo;
  return b;
}

}  // namespace

Options options_of(const AdapterDescriptor& adapter, const OptionText& set) {
  Options options = default_options(adapter);
  for (const auto& [name, text] : set) {
    std::string error;
    if (!set_option_text(adapter, options, name, text, error)) throw std::invalid_argument(error);
  }
  return options;
}

BusRig::BusRig(const AdapterDescriptor& adapter) : BusRig(adapter, native_line(adapter)) {}

BusRig::BusRig(const AdapterDescriptor& adapter, BusConfig line)
    : adapter_(adapter), line_config_(std::move(line)), log_(test_logger()) {
  line_ = std::make_unique<SimLine>(clock_,
                                    character_time(line_config_.baud, line_config_.parity,
                                                   line_config_.data_bits, line_config_.stop_bits),
                                    line_config_.echo);
}

BusRig::~BusRig() {
  if (engine_) engine_->stop();
}

DeviceConfig BusRig::device_config(std::string name, std::uint32_t address,
                                   const OptionText& options) const {
  DeviceConfig c;
  c.name = std::move(name);
  c.bus = line_config_.name;
  c.adapter = adapter_.id;
  c.unit_id = static_cast<std::uint8_t>(devices_.size() + 1);
  c.address = address;
  c.options = options_of(adapter_, options);
  return c;
}

Device& BusRig::add_device(const DeviceConfig& config, bool maintenance) {
  // The daemon's own factory call (gateway.h), on this rig's line.
  std::string error;
  std::unique_ptr<Driver> driver = make_driver(config, adapter_, maintenance, error, &line_config_);
  if (!driver) throw std::invalid_argument(error);
  return add_device(config, std::move(driver));
}

Device& BusRig::add_device(std::string name, std::uint32_t address, const OptionText& options) {
  return add_device(device_config(std::move(name), address, options));
}

Device& BusRig::add_device(const DeviceConfig& config, std::unique_ptr<Driver> driver) {
  if (engine_) throw std::logic_error("add devices before start()");
  devices_.push_back(std::make_unique<Device>(config, adapter_, std::move(driver), log_, now()));
  return *devices_.back();
}

Simulator& BusRig::add_simulator(std::uint32_t address, const OptionText& options) {
  SimEnv env;
  env.address = address;
  env.options = options_of(adapter_, options);
  std::string error;
  std::unique_ptr<Simulator> sim = adapter_.create_simulator(env, error);
  if (!sim) throw std::invalid_argument("the adapter refused the simulator: " + error);
  return add_simulator(std::move(sim));
}

Simulator& BusRig::add_simulator(std::unique_ptr<Simulator> sim) {
  sims_.push_back(std::move(sim));
  line_->add(*sims_.back());
  return *sims_.back();
}

void BusRig::start() {
  std::vector<Station*> stations;
  for (const auto& d : devices_) stations.push_back(d.get());
  engine_ = std::make_unique<BusEngine>(line_config_, stations, clock_, *line_, log_);
  line_->attach(*engine_);
  clock_.on_alarm([this] { engine_->on_alarm(); });
  engine_->start();
  line_->start();
  engine_->line_up(false);
}

std::shared_ptr<WriteOutcome> BusRig::write(Device& d, Table table, std::uint16_t address,
                                            std::vector<std::uint16_t> values,
                                            const Session& session) {
  auto outcome = std::make_shared<WriteOutcome>();
  const Outcome at_once = d.write(
      session, table, address, values, [outcome](Outcome r) { outcome->result = r; }, now());
  if (at_once != Outcome::ok) outcome->result = at_once;
  return outcome;
}

std::optional<Outcome> BusRig::wait(const std::shared_ptr<WriteOutcome>& w, Millis limit) {
  run_until([&] { return w->settled(); }, limit);
  return w->result;
}

std::optional<Outcome> BusRig::write_and_wait(Device& d, Table table, std::uint16_t address,
                                              std::vector<std::uint16_t> values, Millis limit,
                                              const Session& session) {
  return wait(write(d, table, address, std::move(values), session), limit);
}

std::vector<std::uint16_t> BusRig::read(Device& d, Table table, std::uint16_t address,
                                        std::size_t n, const Session& session) {
  std::vector<std::uint16_t> out(n);
  if (d.read(session, table, address, out, now()) != Outcome::ok) out.clear();
  // The client has its reply before it asks anything more, as a PLC that waits for each.
  if (session.fault_reads) {
    session.fault_reads->all_sent();
    session.fault_reads->received();
  }
  return out;
}

std::vector<std::uint16_t> BusRig::read(Device& d, std::string_view point) {
  const MappedPoint* p = d.map().find(point);
  if (p == nullptr) throw std::invalid_argument("no point " + std::string(point));
  const bool bits = p->spec.table == Table::discrete || p->spec.table == Table::coil;
  return read(d, p->spec.table, p->address, bits ? 1 : p->spec.register_count());
}

std::uint32_t BusRig::value(Device& d, std::string_view point) {
  const auto regs = read(d, point);
  if (regs.size() == 2) return (std::uint32_t{regs[0]} << 16) | regs[1];
  return regs.empty() ? 0xFFFFFFFFu : regs[0];
}

std::string BusRig::text(Device& d, std::string_view point) {
  std::string out;
  for (const std::uint16_t r : read(d, point)) {
    for (const auto c : {static_cast<char>(r >> 8), static_cast<char>(r & 0xFF)}) {
      if (c == '\0') return out;
      out.push_back(c);
    }
  }
  return out;
}

}  // namespace drivegate::test
