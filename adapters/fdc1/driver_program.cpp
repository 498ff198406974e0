// The programming of the non-volatile settings (INPUT, "Programming mode + parameters"), which is
// the maintenance action `program`: each prog_<field> write stores a field (done, no traffic);
// 1 to prog_commit validates them all against every limit of the document (program.cpp) and only
// then sends the 22 bytes, in force once the controller's echo equals them.
//
// check() may refuse a commit but may not say why (it has no side effects), and the gateway never
// applies a request check() refused. So prog_message is kept current instead: it always says why
// a commit now would be refused (a field missing or breaking a rule, the controller silent, a
// commit on its way), or, when one would go, why the last one failed. The PLC or `drivegate
// action` reads it after the exception.
#include <cmath>

#include "driver.h"

namespace drivegate::fdc1 {
namespace {

bool is_number(const Value& v) {
  return std::holds_alternative<std::int64_t>(v) || std::holds_alternative<double>(v);
}

}  // namespace

void Fdc1Driver::store_field(const WriteOp& op, std::vector<Value>& fields) {
  const double x = as_double(op.value);
  if (is_volts_field(op.point)) {
    fields[op.point] = x;
  } else {
    fields[op.point] = static_cast<std::int64_t>(std::llround(x));  // rpm, the mode byte
  }
}

WriteCheck Fdc1Driver::judge_point(const WriteOp& op, const std::vector<Value>& fields) const {
  if (!programming_ || op.point < pt::prog_min_rpm || op.point > pt::prog_commit) {
    return WriteCheck::invalid_value;  // no other point of this adapter is writable
  }
  // The gateway checked the point's limits already; a driver handed a WriteOp by anyone else
  // still refuses what the frame cannot carry.
  const PointSpec& spec = points_[op.point];
  const double x = as_double(op.value);
  if (!is_number(op.value) || x < spec.min || x > spec.max) return WriteCheck::invalid_value;
  if (op.point != pt::prog_commit) return WriteCheck::ok;
  const auto blocker = commit_blocker(fields);
  return blocker ? blocker->verdict : WriteCheck::ok;
}

std::optional<Fdc1Driver::Blocker> Fdc1Driver::commit_blocker(
    const std::vector<Value>& fields) const {
  if (prog_state_ != Programming::idle) {
    return Blocker{WriteCheck::refused, "a programming frame is on its way already"};
  }
  ProgramSettings p;
  auto problem = gather_program(fields, p);
  if (!problem) problem = validate_program(p);
  if (problem) return Blocker{WriteCheck::invalid_value, *problem};
  // Heard at least once since start-up or comm_lost: the programming frame needs a listener, and
  // the echo a stream to come back on.
  if (!common_.ready) return Blocker{WriteCheck::refused, "the controller is not streaming"};
  return std::nullopt;
}

// The fields the mode's form needs (standard or special battery system, mode bit 5), or the first
// one missing.
std::optional<std::string> Fdc1Driver::gather_program(const std::vector<Value>& fields,
                                                      ProgramSettings& p) const {
  const auto missing = [&](std::size_t point) {
    return std::holds_alternative<std::monostate>(fields[point]);
  };
  const auto num = [&](std::size_t point) { return as_double(fields[point]); };
  for (const std::size_t f : {pt::prog_min_rpm, pt::prog_max_rpm, pt::prog_mode}) {
    if (missing(f)) return points_[f].name + " is not set";
  }
  p.min_rpm = static_cast<std::uint16_t>(num(pt::prog_min_rpm));
  p.max_rpm = static_cast<std::uint16_t>(num(pt::prog_max_rpm));
  p.mode = static_cast<std::uint8_t>(num(pt::prog_mode));
  if (p.special()) {
    for (const std::size_t f :
         {pt::prog_cut_out_special, pt::prog_cut_in_special, pt::prog_nominal_v}) {
      if (missing(f)) return points_[f].name + " is not set (special battery system)";
    }
    p.cut_out_special = num(pt::prog_cut_out_special);
    p.cut_in_special = num(pt::prog_cut_in_special);
    p.nominal_voltage = num(pt::prog_nominal_v);
    return std::nullopt;
  }
  for (std::size_t f = pt::prog_cut_out_12v; f <= pt::prog_cut_in_42v; ++f) {
    if (missing(f)) return points_[f].name + " is not set (standard battery system)";
  }
  p.cut_out_12v = num(pt::prog_cut_out_12v);
  p.cut_in_12v = num(pt::prog_cut_in_12v);
  p.cut_out_24v = num(pt::prog_cut_out_24v);
  p.cut_in_24v = num(pt::prog_cut_in_24v);
  p.cut_out_42v = num(pt::prog_cut_out_42v);
  p.cut_in_42v = num(pt::prog_cut_in_42v);
  return std::nullopt;
}

WriteStatus Fdc1Driver::apply_point(const WriteOp& op, Ticket t, TimePoint now) {
  if (const auto no = refusal(judge_point(op, values_))) return *no;
  prog_outcome_.reset();  // the last commit's outcome was about the fields as they were
  if (op.point != pt::prog_commit) {
    store_field(op, values_);
    publish_program();
    return WriteStatus::done;
  }
  ProgramSettings p;
  (void)gather_program(values_, p);  // judge_point() found them complete and valid
  prog_sent_ = to_program(p);
  prog_ticket_ = t;
  prog_state_ = Programming::queued;
  due_at_ = now;
  publish_program();
  return WriteStatus::pending;
}

RxVerdict Fdc1Driver::on_echo(const Echo& echo, std::size_t consumed) {
  if (prog_state_ != Programming::awaiting_echo) return {RxKind::foreign, consumed};
  // INPUT programming: "When the parameters are acknowledged and saved to the memory, the device
  // will return the same sequence of bytes".
  if (echo.program == prog_sent_) {
    finish_program(WriteResult::ok, ProgStatus::ok, "");
  } else {
    finish_program(WriteResult::refused, ProgStatus::refused,
                   "the controller's echo differs from the frame sent");
  }
  // The echo of a programming frame carries no status: data_age_ms runs on.
  return {RxKind::ack, consumed};
}

void Fdc1Driver::finish_program(WriteResult r, ProgStatus status, std::string message) {
  completions_.add(prog_ticket_, r);
  prog_state_ = Programming::idle;
  prog_outcome_.emplace(status, std::move(message));
  publish_program();
}

// prog_status: pending while a commit is on its way; the last commit's outcome until a field is
// written again; else invalid when the fields as they stand break a rule, idle when they do not.
// prog_message: why a commit now would be refused, else why the last one failed, else empty.
void Fdc1Driver::publish_program() {
  if (!programming_) return;
  const auto blocker = commit_blocker(values_);
  ProgStatus status = ProgStatus::idle;
  if (prog_state_ != Programming::idle) {
    status = ProgStatus::pending;
  } else if (prog_outcome_) {
    status = prog_outcome_->first;
  } else if (blocker && blocker->verdict == WriteCheck::invalid_value) {
    status = ProgStatus::invalid;
  }
  std::string message;
  if (blocker) {
    message = blocker->why;
  } else if (prog_outcome_) {
    message = prog_outcome_->second;
  }
  values_[pt::prog_status] = static_cast<std::int64_t>(status);
  values_[pt::prog_message] = std::move(message);
}

}  // namespace drivegate::fdc1
