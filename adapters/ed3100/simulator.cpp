#include "simulator.h"

#include <vector>

#include "drivegate/sim_rx.h"
#include "registers.h"

namespace drivegate::ed3100 {
namespace {

// Modbus exception codes (Modbus application protocol 7; the document names none).
constexpr std::uint8_t kIllegalAddress = 0x02;
constexpr std::uint8_t kIllegalValue = 0x03;
constexpr std::uint8_t kDeviceFailure = 0x04;

// Defaults that make the first replies the document's own examples: 00-06 reads 0x1088
// ("03H: read register content"), 00-07 = 00.01 ("10H"), monitor 0x0D00 reads 0x1084 / 0x4148
// (42.28 Hz, stopped: shown while stopped, the reference), 0x0E01 reads FFFF / 0x0148.
constexpr std::uint16_t kDefaultParam0006 = 0x1088;
constexpr std::uint16_t kDefaultParam0007 = 0x0001;
constexpr std::uint16_t kDefaultReference = 0x1084;
constexpr bool kDefaultCommandedReverse = true;  // bit 3 of 0x0148
// State bits the example carries that the simulator never changes: bit 6 (digital frequency
// channel) and bit 8 (not legible in the document's table).
constexpr std::uint16_t kStateConstant = (1u << kStDigitalChannel) | (1u << 8);

// Simulated behaviour, drivegate's choice: ramps of 50.00 Hz/s, a 537 V DC bus (380 V mains).
constexpr int kRampCentiHzPerSecond = 5000;
constexpr std::uint16_t kDcBusVolts = 537;
constexpr std::uint16_t kRatedVolts = 380;
constexpr std::uint16_t kRatedCentiHz = 5000;
// A partial request older than this is stale: RTU frames end with line silence (document,
// "10 ms interval"); generous because a pty delivers in bursts.
constexpr Millis kStaleRx{100};

constexpr std::uint16_t fmt(unsigned decimals_bit, int unit_bit) {
  return static_cast<std::uint16_t>((1u << decimals_bit) | (unit_bit < 0 ? 0u : 1u << unit_bit) |
                                    (1u << kFmtNormal));
}

bool is_param(std::uint16_t reg) {
  return (reg >> 8) <= kParamGroupMax;
}
bool is_monitor(std::uint16_t reg) {
  return reg >= kRegMonitorFirst && reg <= kRegMonitorLast;
}

}  // namespace

Ed3100Simulator::Ed3100Simulator(std::uint8_t address, ReadForm form)
    : address_(address),
      form_(form),
      params_{{0x0006, kDefaultParam0006}, {0x0007, kDefaultParam0007}},
      command_(kCmdStop),
      reference_(kDefaultReference),
      commanded_reverse_(kDefaultCommandedReverse),
      fault_(kNoFault) {}

Bytes Ed3100Simulator::on_receive(ByteView rx, TimePoint now) {
  if (last_rx_ && now - *last_rx_ > kStaleRx) rx_.clear();
  last_rx_ = now;
  rx_.insert(rx_.end(), rx.begin(), rx.end());
  Bytes out;
  while (const auto d = take_decoded(rx_, [](ByteView b) { return decode_request(b); })) {
    if (d->status == DecodeStatus::bad) continue;  // a drive ignores a frame it cannot check
    if (d->frame.address != address_ && d->frame.address != kBroadcast) continue;
    if (silent_) continue;
    Bytes reply = handle(d->frame);
    if (d->frame.address == kBroadcast) continue;  // document, "00H: ... not respond"
    const Bytes sent = finish(std::move(reply));
    out.insert(out.end(), sent.begin(), sent.end());
  }
  return out;
}

Bytes Ed3100Simulator::finish(Bytes reply) {
  if (corrupt_ > 0 && !reply.empty()) {
    --corrupt_;
    reply.back() ^= 0xFF;
  }
  return reply;
}

Bytes Ed3100Simulator::handle(const Request& r) {
  if (locked_ && r.function != kFnRead)
    return encode_exception(address_, r.function, kDeviceFailure);
  switch (r.function) {
    case kFnRead:
      return read(r);
    case kFnWriteSingle:
      if (const auto e = check(r.reg, r.words[0]))
        return encode_exception(address_, r.function, *e);
      store(r.reg, r.words[0]);
      return encode_write_single(address_, r.reg, r.words[0]);
    case kFnWriteMultiple: {
      if (r.count > kMaxWriteWords) return encode_exception(address_, r.function, kIllegalValue);
      for (std::size_t i = 0; i < r.words.size(); ++i) {
        const auto reg = static_cast<std::uint16_t>(r.reg + i);
        if (const auto e = check(reg, r.words[i])) {
          return encode_exception(address_, r.function, *e);
        }
      }
      // The reference before the command, so that a run starts towards the new frequency.
      for (std::size_t i = r.words.size(); i-- > 0;) {
        store(static_cast<std::uint16_t>(r.reg + i), r.words[i]);
      }
      return encode_write_multiple_reply(address_, r.reg, r.count);
    }
    default:
      return encode_exception(address_, r.function, 0x01);
  }
}

Bytes Ed3100Simulator::read(const Request& r) {
  std::vector<std::uint16_t> words;
  if (is_monitor(r.reg)) {
    // Two words whatever the quantity says ("retained data ... does not affect the results").
    const auto [value, format] = monitor(r.reg);
    words = {value, format};
  } else if (r.reg == kRegFault) {
    words = {fault_, state_word()};
  } else if (is_param(r.reg) || r.reg == kRegCommand || r.reg == kRegFrequency) {
    if (r.count == 0 || r.count > kMaxWriteWords) {
      return encode_exception(address_, kFnRead, kIllegalValue);
    }
    for (std::uint16_t i = 0; i < r.count; ++i) {
      const auto reg = static_cast<std::uint16_t>(r.reg + i);
      if (reg == kRegCommand) {
        words.push_back(command_);
      } else if (reg == kRegFrequency) {
        words.push_back(reference_);
      } else if (is_param(reg)) {
        const auto it = params_.find(reg);
        words.push_back(it == params_.end() ? 0 : it->second);
      } else {
        return encode_exception(address_, kFnRead, kIllegalAddress);
      }
    }
  } else {
    return encode_exception(address_, kFnRead, kIllegalAddress);
  }
  return encode_read_reply(address_, r.reg, words, form_);
}

std::optional<std::uint8_t> Ed3100Simulator::check(std::uint16_t reg, std::uint16_t value) const {
  if (reg == kRegCommand) {
    switch (value) {
      case kCmdStop:
        return std::nullopt;
      case kCmdForward:
      case kCmdForwardOneShot:
      case kCmdReverse:
        return fault_ != kNoFault ? std::optional<std::uint8_t>(kDeviceFailure) : std::nullopt;
      default:
        return kIllegalValue;
    }
  }
  if (reg == kRegFrequency || reg == kRegResetDefault || is_param(reg)) return std::nullopt;
  return kIllegalAddress;
}

void Ed3100Simulator::store(std::uint16_t reg, std::uint16_t value) {
  if (reg == kRegCommand) {
    command_ = value;
    if (value == kCmdForward || value == kCmdForwardOneShot) commanded_reverse_ = false;
    if (value == kCmdReverse) commanded_reverse_ = true;
    if (value != kCmdStop && !running_) {
      running_ = true;
      rotating_reverse_ = commanded_reverse_;
    }
  } else if (reg == kRegFrequency) {
    reference_ = value;
  } else if (reg == kRegResetDefault) {
    if ((value & kResetValueDefault) != 0) fault_ = kNoFault;
  } else {
    params_[reg] = value;
  }
}

bool Ed3100Simulator::commanded_run() const {
  return command_ != kCmdStop;
}

Bytes Ed3100Simulator::on_tick(TimePoint now) {
  const Millis dt = last_tick_ ? std::chrono::duration_cast<Millis>(now - *last_tick_) : Millis(0);
  last_tick_ = now;
  accelerating_ = decelerating_ = false;
  if (!running_) return {};
  // Reversing passes through 0 Hz; a stop ramps to 0 Hz and then stops.
  const bool turn = commanded_run() && rotating_reverse_ != commanded_reverse_;
  const int target = commanded_run() && !turn ? reference_ : 0;
  const int step = static_cast<int>(kRampCentiHzPerSecond * dt.count() / 1000);
  int out = output_;
  if (out < target) {
    out = std::min(target, out + step);
    accelerating_ = true;
  } else if (out > target) {
    out = std::max(target, out - step);
    decelerating_ = true;
  }
  output_ = static_cast<std::uint16_t>(out);
  if (output_ == 0 && turn) rotating_reverse_ = commanded_reverse_;
  if (output_ == 0 && !commanded_run()) {
    running_ = false;
    rotating_reverse_ = false;
  }
  return {};
}

std::pair<std::uint16_t, std::uint16_t> Ed3100Simulator::monitor(std::uint16_t reg) const {
  if (const auto it = monitor_override_.find(reg); it != monitor_override_.end()) {
    return it->second;
  }
  const std::uint16_t stopped = running_ ? 0 : static_cast<std::uint16_t>(1u << kFmtStopped);
  std::uint16_t value = 0;
  std::uint16_t format = fmt(kFmtDecimals0, -1);
  switch (reg) {
    case 0x0D00:  // output frequency, 2 decimals, Hz; stopped: the reference
      value = running_ ? output_ : reference_;
      format = fmt(kFmtDecimals2, kFmtHertz);
      break;
    case 0x0D01:  // output current, 1 decimal, A (simulated load)
      value = running_ ? static_cast<std::uint16_t>(15 + output_ / 500) : 0;
      format = fmt(kFmtDecimals1, kFmtAmpere);
      break;
    case 0x0D02:  // output voltage, 0 decimals, V (V/f)
      value = static_cast<std::uint16_t>(running_ ? output_ * kRatedVolts / kRatedCentiHz : 0);
      format = fmt(kFmtDecimals0, kFmtVolt);
      break;
    case 0x0D03:  // DC bus voltage, 0 decimals, V
      value = kDcBusVolts;
      format = fmt(kFmtDecimals0, kFmtVolt);
      break;
    default:
      break;
  }
  return {value, static_cast<std::uint16_t>(format | stopped)};
}

std::uint16_t Ed3100Simulator::state_word() const {
  std::uint16_t w = kStateConstant;
  auto set = [&](unsigned b, bool on) {
    if (on) w = static_cast<std::uint16_t>(w | (1u << b));
  };
  set(kStRunReverse, running_ && rotating_reverse_);
  set(kStPhaseReverse, running_ && rotating_reverse_);
  set(kStCmdReverse, commanded_reverse_);
  set(kStRunning, running_);
  set(kStFault, fault_ != kNoFault);
  set(kStAccelerating, accelerating_);
  set(kStDecelerating, decelerating_);
  return w;
}

}  // namespace drivegate::ed3100
