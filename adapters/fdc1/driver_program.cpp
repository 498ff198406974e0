// The driver's non-volatile programming: prog_* points, prog_commit, the echo.
#include "driver.h"
#include "points.h"

namespace drivegate::fdc1 {
namespace {

struct Field {
  std::size_t point;
  const char* name;
};

}  // namespace

WriteStatus Fdc1Driver::write(std::size_t point, const Value& v, Ticket t, TimePoint now) {
  if (!programming_ || point < pt::prog_min_rpm || point > pt::prog_commit) {
    return WriteStatus::invalid_value;
  }
  const PointSpec& spec = points_[point];
  const double x = as_double(v);
  if (std::holds_alternative<std::monostate>(v) || std::holds_alternative<std::string>(v) ||
      x < spec.min || x > spec.max) {
    return WriteStatus::invalid_value;
  }
  if (point == pt::prog_commit) return commit_program(t, now);
  if (point >= pt::prog_cut_out_12v) {
    values_[point] = x;  // volts
  } else {
    values_[point] = static_cast<std::int64_t>(x + 0.5);  // rpm, mode byte
  }
  return WriteStatus::done;
}

std::optional<std::string> Fdc1Driver::gather_program(ProgramSettings& p) const {
  const auto missing = [&](std::size_t point) {
    return std::holds_alternative<std::monostate>(values_[point]);
  };
  const Field common_fields[] = {{pt::prog_min_rpm, "prog_min_rpm"},
                                 {pt::prog_max_rpm, "prog_max_rpm"},
                                 {pt::prog_mode, "prog_mode"}};
  for (const auto& f : common_fields) {
    if (missing(f.point)) return std::string(f.name) + " is not set";
  }
  const auto num = [&](std::size_t point) { return as_double(values_[point]); };
  p.min_rpm = static_cast<std::uint16_t>(num(pt::prog_min_rpm));
  p.max_rpm = static_cast<std::uint16_t>(num(pt::prog_max_rpm));
  p.mode = static_cast<std::uint8_t>(num(pt::prog_mode));
  const Field standard[] = {
      {pt::prog_cut_out_12v, "prog_cut_out_12v"}, {pt::prog_cut_in_12v, "prog_cut_in_12v"},
      {pt::prog_cut_out_24v, "prog_cut_out_24v"}, {pt::prog_cut_in_24v, "prog_cut_in_24v"},
      {pt::prog_cut_out_42v, "prog_cut_out_42v"}, {pt::prog_cut_in_42v, "prog_cut_in_42v"}};
  const Field special[] = {{pt::prog_cut_out_special, "prog_cut_out_special"},
                           {pt::prog_cut_in_special, "prog_cut_in_special"},
                           {pt::prog_nominal_v, "prog_nominal_v"}};
  if (p.special()) {
    for (const auto& f : special) {
      if (missing(f.point)) return std::string(f.name) + " is not set (special battery system)";
    }
    p.cut_out_special = num(pt::prog_cut_out_special);
    p.cut_in_special = num(pt::prog_cut_in_special);
    p.nominal_voltage = num(pt::prog_nominal_v);
  } else {
    for (const auto& f : standard) {
      if (missing(f.point)) return std::string(f.name) + " is not set (standard battery system)";
    }
    p.cut_out_12v = num(pt::prog_cut_out_12v);
    p.cut_in_12v = num(pt::prog_cut_in_12v);
    p.cut_out_24v = num(pt::prog_cut_out_24v);
    p.cut_in_24v = num(pt::prog_cut_in_24v);
    p.cut_out_42v = num(pt::prog_cut_out_42v);
    p.cut_in_42v = num(pt::prog_cut_in_42v);
  }
  return std::nullopt;
}

WriteStatus Fdc1Driver::commit_program(Ticket t, TimePoint now) {
  if (prog_state_ != Programming::idle) return WriteStatus::refused;  // one at a time
  ProgramSettings p;
  auto problem = gather_program(p);
  if (!problem) problem = validate_program(p);
  if (problem) {
    values_[pt::prog_status] = static_cast<std::int64_t>(ProgStatus::invalid);
    values_[pt::prog_message] = *problem;
    return WriteStatus::invalid_value;
  }
  if (!common_.ready) {
    values_[pt::prog_status] = static_cast<std::int64_t>(ProgStatus::refused);
    values_[pt::prog_message] = std::string("the controller is not streaming");
    return WriteStatus::refused;
  }
  prog_sent_ = to_program(p);
  prog_ticket_ = t;
  prog_state_ = Programming::queued;
  due_at_ = now;
  values_[pt::prog_status] = static_cast<std::int64_t>(ProgStatus::pending);
  values_[pt::prog_message] = std::string();
  return WriteStatus::pending;
}

RxVerdict Fdc1Driver::on_echo(const Echo& echo) {
  if (prog_state_ != Programming::awaiting_echo) return {RxKind::foreign, 0};
  if (echo.program == prog_sent_) {
    finish_program(WriteResult::ok, ProgStatus::ok, "");
  } else {
    finish_program(WriteResult::refused, ProgStatus::refused,
                   "the controller's echo differs from the frame sent");
  }
  return {RxKind::reply, 0};
}

void Fdc1Driver::finish_program(WriteResult r, ProgStatus status, std::string message) {
  complete(prog_ticket_, r);
  prog_state_ = Programming::idle;
  values_[pt::prog_status] = static_cast<std::int64_t>(status);
  values_[pt::prog_message] = std::move(message);
}

}  // namespace drivegate::fdc1
