// TestDriveSimulator: requests in, replies out, and the operator's commands.
#include "simulator.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <utility>

#include "drivegate/sim_text.h"

namespace drivegate::testdrive {
namespace {

constexpr const char* kHelp =
    "state, fault over_current|stall|over_temperature, clear, silent on|off, corrupt N, "
    "refuse N";

constexpr std::array<std::pair<std::string_view, NativeFault>, 3> kFaultNames = {{
    {"over_current", NativeFault::over_current},
    {"stall", NativeFault::stall},
    {"over_temperature", NativeFault::over_temperature},
}};

}  // namespace

Bytes TestDriveSimulator::on_receive(ByteView rx, TimePoint now) {
  (void)now;
  buffer_.insert(buffer_.end(), rx.begin(), rx.end());
  Bytes out;
  while (!buffer_.empty()) {
    const Decoded<Request> d = decode_request(buffer_);
    if (d.status == DecodeStatus::incomplete) break;
    buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(d.consumed));
    if (d.status != DecodeStatus::frame || d.frame.address != address_) continue;
    Bytes reply = answer(d.frame);
    out.insert(out.end(), reply.begin(), reply.end());
  }
  return out;
}

Bytes TestDriveSimulator::answer(const Request& r) {
  if (silent_) return {};  // deaf: it neither takes nor answers anything
  if (refuse_ > 0) {
    --refuse_;
    return encode(refusal(address_, r.op));
  }
  switch (r.op) {
    case Op::read:
      break;
    case Op::run_forward:
    case Op::run_reverse:
      if (fault_ != NativeFault::none) break;  // a tripped drive does not start
      state_ = r.op == Op::run_reverse ? (kStateRunning | kStateReverse) : kStateRunning;
      target_rpm_ = static_cast<std::int16_t>(r.op == Op::run_reverse ? -r.arg : r.arg);
      break;
    case Op::stop:
      state_ = 0;
      target_rpm_ = 0;
      break;
    case Op::reset:
      fault_ = NativeFault::none;
      break;
    case Op::accel:
      if (r.arg > 0) accel_100ms_ = r.arg;
      break;
  }
  Bytes reply =
      encode(Reply{address_, r.op, state_, static_cast<std::uint8_t>(fault_), speed_rpm_});
  if (corrupt_ > 0) {
    --corrupt_;
    reply.back() = static_cast<std::uint8_t>(reply.back() + 1);
  }
  return reply;
}

Bytes TestDriveSimulator::on_tick(TimePoint now) {
  const double seconds = last_tick_ ? std::chrono::duration<double>(now - *last_tick_).count() : 0;
  last_tick_ = now;
  // The ramp to the rpm, kept exact: a slow one moves less than 1 rpm a tick.
  const double step = seconds * kMaxRpm * 10.0 / accel_100ms_;
  ramp_rpm_ += std::clamp(target_rpm_ - ramp_rpm_, -step, step);
  speed_rpm_ = static_cast<std::int16_t>(std::lround(ramp_rpm_));
  return {};
}

std::string TestDriveSimulator::state() const {
  return "state=" + hex(state_, 2) + " running=" + ((state_ & kStateRunning) != 0 ? "1" : "0") +
         " fault=" + std::to_string(static_cast<int>(fault_)) +
         " speed=" + std::to_string(speed_rpm_) + " target=" + std::to_string(target_rpm_) +
         " accel=" + std::to_string(accel_100ms_) + " silent=" + (silent_ ? "on" : "off");
}

std::string TestDriveSimulator::control(std::string_view line, TimePoint now) {
  (void)now;
  const auto w = split_words(line);
  if (w.size() == 1 && w[0] == "state") return state();
  if (w.size() == 1 && w[0] == "clear") {
    fault_ = NativeFault::none;
    return "ok";
  }
  if (w.size() == 2 && w[0] == "fault") {
    for (const auto& [name, code] : kFaultNames) {
      if (w[1] != name) continue;
      fault_ = code;
      state_ = 0;  // a fault stops the motor, at once
      speed_rpm_ = 0;
      ramp_rpm_ = 0;
      target_rpm_ = 0;
      return "ok fault=" + w[1];
    }
  }
  if (w.size() == 2 && w[0] == "silent" && parse_on_off(w[1])) {
    silent_ = *parse_on_off(w[1]);
    return "ok silent=" + w[1];
  }
  if (w.size() == 2 && (w[0] == "corrupt" || w[0] == "refuse")) {
    if (const auto n = parse_unsigned(w[1], 1000)) {
      (w[0] == "corrupt" ? corrupt_ : refuse_) = *n;
      return "ok " + w[0] + "=" + w[1];
    }
  }
  return std::string("error: unknown command '") + std::string(line) + "'; commands: " + kHelp;
}

}  // namespace drivegate::testdrive
