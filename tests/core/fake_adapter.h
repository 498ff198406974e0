// A scriptable adapter for the core's tests: a descriptor with one option of every type, and a
// driver whose answers the test sets and whose calls it records.
#pragma once

#include <deque>
#include <memory>

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
  WriteStatus command(Command c, Ticket t, TimePoint) override {
    commands.push_back(c);
    last_ticket = t;
    return answer;
  }
  WriteStatus setpoint(std::int32_t rpm, Ticket t, TimePoint) override {
    setpoints.push_back(rpm);
    last_ticket = t;
    common_.setpoint_rpm = rpm;
    return setpoint_answer;
  }
  WriteStatus write(std::size_t point, const Value& v, Ticket t, TimePoint) override {
    writes.emplace_back(point, v);
    last_ticket = t;
    return answer;
  }
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
  WriteStatus answer = WriteStatus::pending;
  WriteStatus setpoint_answer = WriteStatus::done;
  std::vector<Command> commands;
  std::vector<std::int32_t> setpoints;
  std::vector<std::pair<std::size_t, Value>> writes;
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

inline const AdapterDescriptor kFakeAdapter = {kAdapterApiVersion,
                                               "fake",
                                               "a scriptable adapter",
                                               kFakeOptions,
                                               std::size(kFakeOptions),
                                               {4800, Parity::odd, 8, 1, true},
                                               1,
                                               31,
                                               1,
                                               false,
                                               make_fake,
                                               no_sim};
inline const AdapterDescriptor kFakeStreamer = {kAdapterApiVersion,
                                                "streamer",
                                                "streams",
                                                nullptr,
                                                0,
                                                {1200, Parity::none, 8, 1, false},
                                                0,
                                                0,
                                                0,
                                                true,
                                                make_fake,
                                                no_sim};

}  // namespace drivegate::test
