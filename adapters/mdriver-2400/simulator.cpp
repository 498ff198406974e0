#include "simulator.h"

#include <algorithm>
#include <cstdio>
#include <sstream>
#include <vector>

#include "drivegate/sim_rx.h"
#include "drivegate/sim_text.h"
#include "faults.h"
#include "rpm_table.h"

namespace drivegate::mdriver {
namespace {

constexpr const char* kHelp =
    "state | fault <name|code> | clear | silent on|off | corrupt N | eeprom fail|ok | temp N | "
    "info <1..3> N | power-cycle";

}  // namespace

Mdriver2400Simulator::Mdriver2400Simulator(std::uint8_t address) : address_(address) {
  power_on();
}

void Mdriver2400Simulator::power_on() {
  buf_.clear();
  last_frame_.reset();
  checked_ = false;
  target_ = 0;
  change_ = kChangeNormal;
  actual_ = 0;
  error_ = 0;
}

Bytes Mdriver2400Simulator::on_receive(ByteView rx, TimePoint now) {
  if (!buf_.empty() && now - last_rx_ > kStaleRx) buf_.clear();
  last_rx_ = now;
  buf_.insert(buf_.end(), rx.begin(), rx.end());
  Bytes out;
  while (const auto d = take_decoded(buf_, [](ByteView b) { return decode(b); })) {
    if (d->status == DecodeStatus::bad) {
      ++ignored_;  // "異常信号": ignored, no return signal
      continue;
    }
    Bytes reply = handle(d->frame, now);
    if (reply.empty() || silent_) continue;
    if (corrupt_ > 0) {
      --corrupt_;
      reply.back() = static_cast<std::uint8_t>(reply.back() ^ 0x5A);
    }
    out.insert(out.end(), reply.begin(), reply.end());
  }
  return out;
}

Bytes Mdriver2400Simulator::handle(const Frame& f, TimePoint now) {
  // Section 2: answer only frames addressed to this driver, to the address they came from.
  if (f.dst != address_) return {};
  if (f.cmd == static_cast<std::uint8_t>(Cmd::check)) {
    const auto code = parse_check(f);
    if (!code) return ++ignored_, Bytes{};
    ++frames_;
    last_frame_ = now;
    if (eeprom_ok_ && *code == kFixedCode) {
      checked_ = true;
      return encode_check_reply(address_, f.src, *code);
    }
    return encode_check_reply(address_, f.src, kFixedCodeError);
  }
  const auto req = parse_run_request(f);
  if (!req) return ++ignored_, Bytes{};
  ++frames_;
  last_frame_ = now;
  // Not in the document: before a good fixed-code check the driver does not take run data.
  if (!checked_) return ++ignored_, Bytes{};
  if (req->code == kCodeResetStop) error_ = 0;  // [00]: error reset & stop
  target_ = req->code;
  change_ = req->change;
  RunReply r;
  r.target_code = target_;
  r.actual_code = actual_;
  r.error_code = error_;
  r.ipm_temp_c = temp_c_;
  r.info = info_;
  return encode_run_reply(address_, f.src, r);
}

std::uint8_t Mdriver2400Simulator::effective_target() const {
  if (error_ != 0 || target_ <= kCodeStopMax) return 0;
  // Not in the document: codes 0x0F..0x1B (under the lowest running speed) run at 0x1C.
  return std::max(target_, kCodeLowestRun);
}

Bytes Mdriver2400Simulator::on_tick(TimePoint now) {
  if (last_frame_ && now - *last_frame_ >= kSilenceTrip && error_ == 0) {
    error_ = kCommErrorCode;  // and the motor stops
    actual_ = 0;
    last_frame_.reset();
  }
  while (now - last_step_ >= kRampStep) {
    last_step_ = (last_step_ == TimePoint{}) ? now : last_step_ + kRampStep;
    const std::uint8_t goal = effective_target();
    if (goal == 0 && actual_ <= kCodeLowestRun) {
      actual_ = 0;  // under the lowest running speed the motor stops
    } else if (actual_ < goal) {
      actual_ = std::max<std::uint8_t>(static_cast<std::uint8_t>(actual_ + 1), kCodeLowestRun);
    } else if (actual_ > goal) {
      --actual_;
    }
  }
  return {};
}

std::string Mdriver2400Simulator::state() const {
  std::ostringstream s;
  s << "address=" << hex(address_, 2, HexCase::lower) << " checked=" << (checked_ ? 1 : 0)
    << " eeprom=" << (eeprom_ok_ ? "ok" : "fail") << " target=" << hex(target_, 2, HexCase::lower)
    << " change=" << hex(change_, 2, HexCase::lower)
    << " actual=" << hex(actual_, 2, HexCase::lower)
    << " rpm=" << (actual_ == 0 ? 0 : rpm_of_code(actual_))
    << " error=" << hex(error_, 2, HexCase::lower) << " temp=" << unsigned{temp_c_}
    << " info=" << hex(info_[0], 2, HexCase::lower) << "," << hex(info_[1], 2, HexCase::lower)
    << "," << hex(info_[2], 2, HexCase::lower) << " silent=" << (silent_ ? "on" : "off")
    << " corrupt=" << corrupt_ << " frames=" << frames_ << " ignored=" << ignored_;
  return s.str();
}

std::string Mdriver2400Simulator::control(std::string_view line, TimePoint now) {
  const auto w = split_words(line);
  if (w.empty()) return std::string("error: empty command; commands: ") + kHelp;
  const std::string& cmd = w[0];
  if (cmd == "state" && w.size() == 1) return state();
  if (cmd == "fault" && w.size() == 2) {
    std::optional<std::uint8_t> code = parse_uint<std::uint8_t>(w[1]);
    if (!code) {
      if (auto e = find_error(w[1])) code = e->code;
    }
    if (!code) {
      // Unified names as aliases: the first row that maps to the fault.
      for (const auto& e : error_codes()) {
        if (to_string(e.fault) == w[1]) {
          code = e.code;
          break;
        }
      }
    }
    if (!code || *code == 0) {
      std::string names;
      for (const auto& e : error_codes()) names += " " + std::string(e.name);
      return "error: unknown fault '" + w[1] + "'; names:" + names + " (or a code 1..255)";
    }
    error_ = *code;
    actual_ = 0;  // every error of the table stops the motor
    return "ok error=" + hex(error_, 2, HexCase::lower);
  }
  if (cmd == "clear" && w.size() == 1) {
    error_ = 0;
    return "ok";
  }
  if (cmd == "silent" && w.size() == 2 && parse_on_off(w[1])) {
    silent_ = *parse_on_off(w[1]);
    return "ok silent=" + w[1];
  }
  if (cmd == "corrupt" && w.size() == 2) {
    if (auto n = parse_uint<std::uint8_t>(w[1])) {
      corrupt_ = *n;
      return "ok corrupt=" + std::to_string(corrupt_);
    }
  }
  if (cmd == "eeprom" && w.size() == 2 && (w[1] == "fail" || w[1] == "ok")) {
    eeprom_ok_ = w[1] == "ok";
    if (!eeprom_ok_) checked_ = false;
    return "ok eeprom=" + w[1];
  }
  if (cmd == "temp" && w.size() == 2) {
    if (auto t = parse_uint<std::uint8_t>(w[1])) {
      temp_c_ = *t;
      return "ok temp=" + std::to_string(temp_c_);
    }
  }
  if (cmd == "info" && w.size() == 3) {
    const auto i = parse_uint<std::uint8_t>(w[1]);
    const auto v = parse_uint<std::uint8_t>(w[2]);
    if (i && v && *i >= 1 && *i <= 3) {
      info_[*i - 1] = *v;
      return "ok";
    }
  }
  if (cmd == "power-cycle" && w.size() == 1) {
    power_on();
    last_step_ = now;
    return "ok";
  }
  return "error: bad command '" + std::string(line) + "'; commands: " + kHelp;
}

}  // namespace drivegate::mdriver
