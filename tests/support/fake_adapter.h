// A scriptable adapter for the core's tests: a descriptor with one option of every type, and a
// driver whose answers the test sets and whose calls it records.
#pragma once

#include <deque>
#include <memory>
#include <optional>

#include "drivegate/adapter.h"

namespace drivegate::test {

class FakeDriver final : public Driver {
 public:
  explicit FakeDriver(const DeviceEnv& env) : env_(env) {
    PointSpec temp;
    temp.name = "temperature";
    temp.table = Table::input;
    temp.type = PointType::i16;
    temp.scale = 0.1;
    temp.unit = "degC";
    points_.push_back(temp);
    PointSpec limit;
    limit.name = "limit";
    limit.table = Table::holding;
    limit.type = PointType::u32;
    limit.min = 10;
    limit.max = 100000;
    points_.push_back(limit);
    PointSpec pressure;
    pressure.name = "pressure";
    pressure.table = Table::input;
    pressure.type = PointType::f32;
    points_.push_back(pressure);
    PointSpec gain;  // a writable float: holding 18..19
    gain.name = "gain";
    gain.table = Table::holding;
    gain.type = PointType::f32;
    points_.push_back(gain);
    values_.resize(points_.size());
  }
  DriverTraits traits() const override { return traits_; }
  const std::vector<PointSpec>& points() const override { return points_; }
  const std::vector<Value>& values() const override { return values_; }
  const CommonState& common() const override { return common_; }
  std::optional<Exchange> next_exchange(TimePoint) override {
    if (outbox.empty()) return std::nullopt;
    Exchange e = outbox.front();
    outbox.pop_front();
    return e;
  }
  TimePoint wake_at() const override { return TimePoint::max(); }
  RxVerdict on_receive(ByteView rx, TimePoint) override { return {RxKind::noise, rx.size()}; }
  void on_no_reply(TimePoint) override { ++no_replies; }
  void on_comm_lost(TimePoint) override { ++comm_losts; }
  WriteCheck check(std::span<const WriteOp> request) const override {
    ++checks;
    for (const WriteOp& op : request) {
      if (op.target == WriteOp::Target::command && op.command == refuse_command) {
        return WriteCheck::refused;
      }
    }
    return check_answer;
  }
  WriteStatus apply(const WriteOp& op, Ticket t, TimePoint) override {
    last_ticket = t;
    switch (op.target) {
      case WriteOp::Target::command:
        commands.push_back(op.command);
        fault_seen.push_back(op.fault_seen);
        return answer;
      case WriteOp::Target::setpoint:
        setpoints.push_back(op.rpm);
        common_.setpoint_rpm = op.rpm;
        return setpoint_answer;
      case WriteOp::Target::point:
        writes.emplace_back(op.point, op.value);
        return answer;
      case WriteOp::Target::forward:  // only a forwarding one takes them
        if (!forwarding) break;
        forwarded.push_back(op.pdu);
        return answer;
    }
    return WriteStatus::invalid_value;
  }
  bool forwards() const override { return forwarding; }
  void take_completions(std::vector<Completion>& out) override {
    out.insert(out.end(), completions.begin(), completions.end());
    completions.clear();
  }

  DeviceEnv env_;
  DriverTraits traits_;
  std::vector<PointSpec> points_;
  std::vector<Value> values_;
  CommonState common_;
  std::deque<Exchange> outbox;
  WriteCheck check_answer = WriteCheck::ok;
  std::optional<Command> refuse_command;  // check() refuses a request carrying it
  mutable int checks = 0;
  WriteStatus answer = WriteStatus::pending;
  WriteStatus setpoint_answer = WriteStatus::done;
  std::vector<Command> commands;
  std::vector<std::optional<TimePoint>> fault_seen;  // each command's WriteOp::fault_seen
  std::vector<std::int32_t> setpoints;
  std::vector<std::pair<std::size_t, Value>> writes;
  bool forwarding = false;       // a pass-through driver: every request is forwarded
  std::vector<Bytes> forwarded;  // the forward parts applied, their PDUs
  std::vector<Completion> completions;
  Ticket last_ticket = 0;
  int no_replies = 0;
  int comm_losts = 0;
};

inline const OptionSpec kFakeOptions[] = {
    {"count", OptionType::integer, "4", "an integer", 1, 10},
    {"ratio", OptionType::real, "0.5", "a number", 0.0, 1.0},
    {"enabled", OptionType::boolean, "false", "a switch"},
    {"mode", OptionType::string, "normal", "a choice", 0, 0, "normal|continuous"},
    {"names", OptionType::string_list, "a,b", "a list"},
};

inline std::unique_ptr<Driver> make_fake(const DeviceEnv& env, std::string& error) {
  if (env.options.has("count") && env.options.integer("count") == 7) {
    error = "count 7 is unlucky";
    return nullptr;
  }
  return std::make_unique<FakeDriver>(env);
}
inline std::unique_ptr<Simulator> no_sim(const SimEnv&, std::string& error) {
  error = "no simulator";
  return nullptr;
}

inline const AdapterDescriptor kFakeAdapter = {.api_version = kAdapterApiVersion,
                                               .id = "fake",
                                               .summary = "a scriptable adapter",
                                               .options = kFakeOptions,
                                               .option_count = std::size(kFakeOptions),
                                               .line = {4800, Parity::odd, 8, 1, true},
                                               .address_min = 1,
                                               .address_max = 31,
                                               .default_address = 1,
                                               .streaming = false,
                                               .create_driver = make_fake,
                                               .create_simulator = no_sim,
                                               .demo = {}};
inline const AdapterDescriptor kFakeStreamer = {.api_version = kAdapterApiVersion,
                                                .id = "streamer",
                                                .summary = "streams",
                                                .options = nullptr,
                                                .option_count = 0,
                                                .line = {1200, Parity::none, 8, 1, false},
                                                .address_min = 0,
                                                .address_max = 0,
                                                .default_address = 0,
                                                .streaming = true,
                                                .create_driver = make_fake,
                                                .create_simulator = no_sim,
                                                .demo = {}};
// Polled like "fake" and framed like it (4800 8O1), but on a two-wire line: no echo. Sharing a
// bus with "fake" needs the [[bus]] to say which echo holds.
inline const AdapterDescriptor kFakeQuiet = {.api_version = kAdapterApiVersion,
                                             .id = "quiet",
                                             .summary = "a fake without echo",
                                             .options = nullptr,
                                             .option_count = 0,
                                             .line = {4800, Parity::odd, 8, 1, false},
                                             .address_min = 0,
                                             .address_max = 0,
                                             .default_address = 0,
                                             .streaming = false,
                                             .create_driver = make_fake,
                                             .create_simulator = no_sim,
                                             .demo = {}};

}  // namespace drivegate::test
