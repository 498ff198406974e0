#include "adapter_bench.h"

#include <bit>
#include <stdexcept>
#include <utility>

#include "gateway/value_codec.h"

namespace drivegate::test {

AdapterBench::AdapterBench(const AdapterDescriptor& adapter, const BenchSetup& setup)
    : rig(adapter) {
  const std::uint32_t address = setup.address.value_or(adapter.default_address);
  DeviceConfig c = rig.device_config("drive", address, setup.options);
  c.poll_interval = setup.poll;
  c.budget = setup.budget;
  drive = &rig.add_device(c, setup.maintenance);
  sim = &rig.add_simulator(address, setup.sim_options.value_or(setup.options));
  rig.start();
}

bool AdapterBench::until_online(Millis idle, Millis limit) {
  if (!rig.run_until([&] { return drive->online(); }, limit)) return false;
  rig.run_for(idle);
  return true;
}

bool AdapterBench::until_reads(std::string_view point, std::uint32_t value, Millis limit) {
  return rig.run_until([&] { return read(point) == value; }, limit);
}

bool AdapterBench::run_forward_at(std::uint16_t rpm) {
  return write({common_block::cmd::run_forward, rpm}) == Outcome::ok;
}

testing::AssertionResult AdapterBench::stores_without_traffic(std::uint16_t rpm) {
  const std::size_t before = rig.sent().size();
  const auto w = start_write({rpm}, common_block::kSetpointRegister);
  if (w->result != Outcome::ok) {
    return testing::AssertionFailure()
           << "the setpoint was not taken at once: "
           << (w->result ? static_cast<int>(*w->result) : -1) << " (-1: still pending)";
  }
  if (rig.sent().size() != before) {
    return testing::AssertionFailure() << rig.sent().size() - before << " frames went out";
  }
  if (read("setpoint_rpm") != rpm) {
    return testing::AssertionFailure() << "setpoint_rpm reads " << read("setpoint_rpm");
  }
  return testing::AssertionSuccess();
}

testing::AssertionResult AdapterBench::runs_from_stopped(std::uint16_t rpm, const Bytes& frame,
                                                         std::chrono::nanoseconds within) {
  if (auto stored = stores_without_traffic(rpm); !stored) return stored;
  const TimePoint asked = rig.now();
  const auto run = start_write({common_block::cmd::run_forward});
  if (auto waits = not_yet_in_force(*run, "command", common_block::cmd::stop); !waits) {
    return waits << " (the run before the drive confirmed it)";
  }
  if (const auto result = rig.wait(run); result != Outcome::ok) {
    return testing::AssertionFailure()
           << "the run ended " << (result ? static_cast<int>(*result) : -1) << " (-1: never)";
  }
  const std::vector<TimePoint> sent = times_of(frame, asked);
  if (sent.size() != 1) {
    return testing::AssertionFailure() << "the run frame went out " << sent.size() << " times";
  }
  if (sent[0] - asked > within) {
    return testing::AssertionFailure()
           << "the run frame went out " << (sent[0] - asked).count() << " ns after the write";
  }
  if (read("command") != common_block::cmd::run_forward ||
      (status() & common_block::kRunning) == 0 || (status() & common_block::kCommandPending) != 0) {
    return testing::AssertionFailure()
           << "once confirmed: command " << read("command") << ", status " << status();
  }
  return testing::AssertionSuccess();
}

testing::AssertionResult AdapterBench::not_yet_in_force(const WriteOutcome& w,
                                                        std::string_view point,
                                                        std::uint32_t in_force) {
  if (w.settled()) {
    return testing::AssertionFailure() << "settled " << static_cast<int>(*w.result);
  }
  if (read(point) != in_force) {
    return testing::AssertionFailure() << point << " reads " << read(point) << ", not " << in_force;
  }
  if ((status() & common_block::kCommandPending) == 0) {
    return testing::AssertionFailure() << "the command-pending bit is clear";
  }
  return testing::AssertionSuccess();
}

std::optional<Outcome> AdapterBench::write(std::vector<std::uint16_t> values,
                                           std::uint16_t address) {
  return rig.write_and_wait(*drive, Table::holding, address, std::move(values));
}

std::shared_ptr<WriteOutcome> AdapterBench::start_write(std::vector<std::uint16_t> values,
                                                        std::uint16_t address) {
  return rig.write(*drive, Table::holding, address, std::move(values));
}

std::optional<Outcome> AdapterBench::write(std::string_view point,
                                           std::vector<std::uint16_t> values) {
  return write(std::move(values), address_of(point));
}

std::shared_ptr<WriteOutcome> AdapterBench::start_write(std::string_view point,
                                                        std::vector<std::uint16_t> values) {
  return start_write(std::move(values), address_of(point));
}

std::shared_ptr<WriteOutcome> AdapterBench::start_point_write(std::string_view first,
                                                              const std::vector<double>& values) {
  const std::uint16_t start = address_of(first);
  std::vector<std::uint16_t> regs;
  std::uint16_t address = start;
  for (const double v : values) {
    const MappedPoint* at = drive->map().at(Table::holding, address);
    if (at == nullptr)
      throw std::invalid_argument("no holding point at " + std::to_string(address));
    std::vector<std::uint16_t> out(at->spec.register_count());
    encode_value(at->spec, Value{v}, out);
    regs.insert(regs.end(), out.begin(), out.end());
    address = static_cast<std::uint16_t>(address + out.size());
  }
  return start_write(std::move(regs), start);
}

std::optional<Outcome> AdapterBench::write_point(std::string_view point, double value) {
  return rig.wait(start_point_write(point, {value}));
}

std::uint16_t AdapterBench::address_of(std::string_view point) const {
  const MappedPoint* p = drive->map().find(point);
  if (p == nullptr) throw std::invalid_argument("no point " + std::string(point));
  return p->address;
}

std::int32_t AdapterBench::read_i16(std::string_view point) {
  return static_cast<std::int16_t>(static_cast<std::uint16_t>(read(point)));
}

float AdapterBench::read_f32(std::string_view point) {
  return std::bit_cast<float>(read(point));
}

std::uint16_t AdapterBench::input(std::uint16_t address) {
  const auto regs = rig.read(*drive, Table::input, address, 1);
  return regs.empty() ? 0xFFFF : regs[0];
}

std::vector<Bytes> AdapterBench::frames(TimePoint from) const {
  std::vector<Bytes> out;
  for (const auto& f : rig.sent()) {
    if (f.at >= from) out.push_back(f.bytes);
  }
  return out;
}

std::vector<Bytes> AdapterBench::frames_after(std::size_t mark) const {
  std::vector<Bytes> out;
  for (std::size_t i = mark; i < rig.sent().size(); ++i) out.push_back(rig.sent()[i].bytes);
  return out;
}

std::vector<TimePoint> AdapterBench::times_of(const Bytes& frame, TimePoint from) const {
  std::vector<TimePoint> out;
  for (const auto& f : rig.sent()) {
    if (f.at >= from && f.bytes == frame) out.push_back(f.at);
  }
  return out;
}

std::size_t AdapterBench::count(const Bytes& frame, TimePoint from) const {
  return times_of(frame, from).size();
}

std::chrono::nanoseconds AdapterBench::on_wire(std::size_t bytes) const {
  return character_time(rig.adapter().line) * static_cast<long>(bytes);
}

bool AdapterBench::sim_has(std::string_view key_value) {
  return (" " + control("state") + " ").find(" " + std::string(key_value) + " ") !=
         std::string::npos;
}

}  // namespace drivegate::test
