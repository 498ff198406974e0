#include "device.h"

#include <algorithm>
#include <limits>

#include "value_codec.h"

namespace drivegate {

using modbus::Exception;

// A Modbus write in flight: answered once every point write it made has settled.
struct Device::Batch {
  modbus::WriteDone done;
  int outstanding = 0;
  Exception result = Exception::none;
  bool submitting = true;  // still submitting: do not answer yet

  void settle(Exception e) {
    if (result == Exception::none) result = e;
    --outstanding;
    finish_if_done();
  }
  void finish_if_done() {
    if (submitting || outstanding > 0 || !done) return;
    auto d = std::move(done);
    done = nullptr;
    d(result);
  }
};

namespace {

Exception to_exception(WriteResult r) {
  switch (r) {
    case WriteResult::ok:
      return Exception::none;
    case WriteResult::refused:
      return Exception::server_device_failure;
    case WriteResult::no_response:
      return Exception::gateway_target_failed;
  }
  return Exception::server_device_failure;
}

std::uint32_t clamp_u32(long long v) {
  return static_cast<std::uint32_t>(
      std::clamp<long long>(v, 0, std::numeric_limits<std::uint32_t>::max()));
}

}  // namespace

Device::Device(DeviceConfig config, const AdapterDescriptor& adapter,
               std::unique_ptr<Driver> driver, std::shared_ptr<spdlog::logger> log, TimePoint now)
    : config_(std::move(config)),
      adapter_(adapter),
      driver_(std::move(driver)),
      traits_(driver_->traits()),
      map_(driver_->points()),
      log_(std::move(log)),
      last_good_(now),
      failsafe_(config_.failsafe.timeout),
      last_tick_(now) {
  for (int t = 0; t < 4; ++t) image_[t].assign(map_.size(static_cast<Table>(t)), 0);
  refresh_image(now);
}

bool Device::online() const {
  return ever_good_ && !comm_lost_ && driver_->common().ready;
}

void Device::frame_good(TimePoint now) {
  ++counters_.frames_good;
  last_good_ = now;
  ever_good_ = true;
  failures_ = 0;
  probe_at_ = {};
  if (comm_lost_) {
    comm_lost_ = false;
    log_->info("device {}: answering again", config_.name);
  }
}

void Device::turn_failed(TimePoint now) {
  ++failures_;
  // Back off a silent device: the pause doubles from one poll interval up to backoff_max, so a
  // dead drive costs its bus little while it is still probed.
  const auto shift = std::min(failures_ - 1, 10);
  const auto pause = std::min<Millis>(config_.poll_interval * (1 << shift), config_.backoff_max);
  probe_at_ = failures_ > 1 ? now + pause : TimePoint{};
}

void Device::housekeeping(TimePoint now) {
  if (!comm_lost_ && now - last_good_ > traits_.comm_timeout) {
    comm_lost_ = true;
    log_->warn("device {}: no good frame for {} ms: comm_lost", config_.name,
               traits_.comm_timeout.count());
    driver_->on_comm_lost(now);
    sync(now);
    fail_pending(Exception::gateway_target_failed);
  }
  for (auto it = pending_.begin(); it != pending_.end();) {
    if (now >= it->second.deadline) {
      auto batch = it->second.batch;
      it = pending_.erase(it);
      batch->settle(Exception::gateway_target_failed);
    } else {
      ++it;
    }
  }
  last_tick_ = now;
  failsafe_tick(now);
  refresh_dynamic(now);
}

void Device::fail_pending(Exception why) {
  auto pending = std::move(pending_);
  pending_.clear();
  for (auto& [ticket, p] : pending) p.batch->settle(why);
}

void Device::sync(TimePoint now) {
  completions_.clear();
  driver_->take_completions(completions_);
  for (const auto& c : completions_) settle(c.ticket, c.result);
  refresh_image(now);
  log_transitions();
}

void Device::settle(Ticket t, WriteResult r) {
  const auto it = pending_.find(t);
  if (it == pending_.end()) return;  // already timed out
  auto batch = it->second.batch;
  pending_.erase(it);
  batch->settle(to_exception(r));
}

void Device::refresh_image(TimePoint now) {
  const auto& values = driver_->values();
  for (const auto& p : map_.points()) {
    if (p.common) continue;
    const bool bits = p.spec.table == Table::discrete || p.spec.table == Table::coil;
    auto regs = registers(p.spec.table).subspan(p.address, bits ? 1 : p.spec.register_count());
    const Value& v = p.index < values.size() ? values[p.index] : Value{};
    if (bits) {
      regs[0] = as_double(v) != 0.0 ? 1 : 0;
    } else {
      encode_value(p.spec, v, regs);
    }
  }
  const CommonState& c = driver_->common();
  auto hr = registers(Table::holding);
  hr[0] = static_cast<std::uint16_t>(c.command);
  hr[1] = static_cast<std::uint16_t>(
      static_cast<std::int16_t>(std::clamp<std::int32_t>(c.setpoint_rpm, -32768, 32767)));
  hr[2] = heartbeat_;
  refresh_dynamic(now);
}

// The parts of the common block that change with time or with the line, not with the driver.
void Device::refresh_dynamic(TimePoint now) {
  const CommonState& c = driver_->common();
  FaultSet faults = c.faults;
  if (comm_lost_) faults.set(Fault::comm_lost);
  std::uint16_t status = 0;
  const auto bit = [&](StatusBit b, bool on) {
    if (on) status |= static_cast<std::uint16_t>(1u << static_cast<unsigned>(b));
  };
  bit(StatusBit::online, online());
  bit(StatusBit::running, c.running);
  bit(StatusBit::fault, !faults.empty());
  bit(StatusBit::warning, c.warning);
  bit(StatusBit::comm_lost, comm_lost_);
  bit(StatusBit::failsafe, failsafe_.latched());
  bit(StatusBit::command_pending, !pending_.empty());

  auto in = registers(Table::input);
  const auto put32 = [&](std::size_t at, std::uint32_t v) {
    in[at] = static_cast<std::uint16_t>(v >> 16);
    in[at + 1] = static_cast<std::uint16_t>(v & 0xFFFF);
  };
  in[0] = status;
  in[1] = static_cast<std::uint16_t>(most_severe(faults));
  put32(2, faults.bits());
  put32(4, c.native_fault);
  in[6] = static_cast<std::uint16_t>(
      static_cast<std::int16_t>(std::clamp<std::int32_t>(c.speed_rpm, -32768, 32767)));
  const auto age = std::chrono::duration_cast<Millis>(now - last_good_).count();
  put32(7, ever_good_ ? clamp_u32(age) : std::numeric_limits<std::uint32_t>::max());
  put32(9, counters_.frames_good);
  put32(11, counters_.bad_checksum);
  put32(13, counters_.timeouts);
  put32(15, counters_.retries);
  put32(17, counters_.nacks);
  if (bus_counters_ != nullptr) {
    put32(19, bus_counters_->exchanges);
    put32(21, bus_counters_->timeouts);
    put32(23, bus_counters_->echo_errors);
    put32(25, bus_counters_->noise_bytes);
    put32(27, bus_counters_->reopens);
  }
  put32(29, counters_.foreign);
  auto di = registers(Table::discrete);
  for (std::size_t b = 0; b < kStatusBitNames.size(); ++b) di[b] = (status >> b) & 1u;
}

void Device::log_transitions() {
  const bool on = online();
  if (on != logged_online_) {
    logged_online_ = on;
    if (on) log_->info("device {}: online", config_.name);
  }
  const FaultSet faults = driver_->common().faults;
  if (faults != logged_faults_) {
    logged_faults_ = faults;
    if (faults.empty()) {
      log_->info("device {}: faults cleared", config_.name);
    } else {
      log_->warn("device {}: fault {} (native 0x{:X}, mask 0x{:X})", config_.name,
                 to_string(most_severe(faults)), driver_->common().native_fault, faults.bits());
    }
  }
}

Exception Device::read(Table table, std::uint16_t address, std::span<std::uint16_t> out,
                       TimePoint now) {
  const auto regs = registers(table);
  if (std::size_t{address} + out.size() > regs.size() ||
      map_.mapped_from(table, address) < out.size()) {
    return Exception::illegal_data_address;
  }
  if (table == Table::input || table == Table::discrete) refresh_dynamic(now);
  std::copy_n(regs.begin() + address, out.size(), out.begin());
  return Exception::none;
}

Exception Device::validate(Table table, std::uint16_t address, std::span<const std::uint16_t> in,
                           std::vector<PointWrite>& writes) const {
  const bool bits = table == Table::coil;
  std::size_t i = 0;
  while (i < in.size()) {
    const auto at = static_cast<std::uint16_t>(address + i);
    const MappedPoint* p = map_.at(table, at);
    // A write must start at a point and cover all its registers.
    if (p == nullptr || p->address != at) return Exception::illegal_data_address;
    const std::size_t count = bits ? 1 : p->spec.register_count();
    if (i + count > in.size()) return Exception::illegal_data_address;
    if (p->spec.access() != Access::read_write) return Exception::illegal_data_address;
    Value v;
    if (bits) {
      v = std::int64_t{in[i] != 0 ? 1 : 0};
    } else {
      auto decoded = decode_value(p->spec, in.subspan(i, count));
      if (!decoded) return Exception::illegal_data_value;
      v = std::move(*decoded);
      const double x = as_double(v);
      if ((p->spec.min != 0.0 || p->spec.max != 0.0) && (x < p->spec.min || x > p->spec.max)) {
        return Exception::illegal_data_value;
      }
    }
    writes.push_back({p, std::move(v)});
    i += count;
  }
  return Exception::none;
}

WriteStatus Device::submit(const PointWrite& w, Ticket t, TimePoint now) {
  const auto as_int = [&] { return static_cast<std::int64_t>(as_double(w.value)); };
  if (!w.point->common) return driver_->write(w.point->index, w.value, t, now);
  switch (w.point->common_id) {
    case CommonPoint::command: {
      const auto c = command_from_value(static_cast<std::uint16_t>(as_int()));
      if (!c) return WriteStatus::invalid_value;
      return driver_->command(*c, t, now);
    }
    case CommonPoint::setpoint_rpm:
      return driver_->setpoint(static_cast<std::int32_t>(as_int()), t, now);
    case CommonPoint::heartbeat:
      heartbeat_ = static_cast<std::uint16_t>(as_int());
      return WriteStatus::done;
    default:
      return WriteStatus::invalid_value;
  }
}

Exception Device::write(Table table, std::uint16_t address, std::span<const std::uint16_t> in,
                        modbus::WriteDone done, TimePoint now) {
  return apply(table, address, in, std::move(done), now, Origin::plc);
}

Exception Device::apply(Table table, std::uint16_t address, std::span<const std::uint16_t> in,
                        modbus::WriteDone done, TimePoint now, Origin origin) {
  std::vector<PointWrite> writes;
  if (const Exception e = validate(table, address, in, writes); e != Exception::none) return e;
  const auto is_common = [](const PointWrite& w, CommonPoint id) {
    return w.point->common && w.point->common_id == id;
  };
  // A valid write to command, setpoint or heartbeat proves the PLC is there, whatever the
  // drive then makes of it (even 0x0B while comm_lost).
  if (origin == Origin::plc && std::any_of(writes.begin(), writes.end(), [&](const PointWrite& w) {
        return is_common(w, CommonPoint::command) || is_common(w, CommonPoint::setpoint_rpm) ||
               is_common(w, CommonPoint::heartbeat);
      })) {
    failsafe_.fed(now);
  }
  // One request writing setpoint and command together means "run at this speed": the setpoint
  // applies first, whatever the address order.
  std::stable_partition(writes.begin(), writes.end(), [](const PointWrite& w) {
    return !(w.point->common && w.point->common_id == CommonPoint::command);
  });
  // A drive that stopped answering cannot take a command: say so now rather than after a
  // timeout. The heartbeat alone is the gateway's and always succeeds.
  const bool heartbeat_only = writes.size() == 1 && writes[0].point->common &&
                              writes[0].point->common_id == CommonPoint::heartbeat;
  if (comm_lost_ && !heartbeat_only) return Exception::gateway_target_failed;

  auto batch = std::make_shared<Batch>();
  batch->done = std::move(done);
  for (const auto& w : writes) {
    const Ticket t = next_ticket_++;
    const WriteStatus s = submit(w, t, now);
    const bool taken = s == WriteStatus::pending || s == WriteStatus::done;
    if (origin == Origin::plc && taken && is_common(w, CommonPoint::command)) {
      const auto c = command_from_value(static_cast<std::uint16_t>(as_double(w.value)));
      if ((c == Command::run_forward || c == Command::run_reverse) && failsafe_.reset(now)) {
        log_->info("device {}: failsafe reset by {} from Modbus", config_.name, to_string(*c));
      }
    }
    if (s == WriteStatus::pending) {
      ++batch->outstanding;
      pending_[t] = Pending{batch, now + traits_.write_timeout};
      continue;
    }
    if (s == WriteStatus::invalid_value || s == WriteStatus::refused) {
      const Exception e = s == WriteStatus::invalid_value ? Exception::illegal_data_value
                                                          : Exception::server_device_failure;
      if (batch->outstanding == 0) {
        sync(now);
        return e;  // nothing of this request is in flight: answer at once
      }
      batch->result = e;
      break;  // do not apply the rest of a request that failed part-way
    }
  }
  batch->submitting = false;
  sync(now);
  if (!pending_.empty() && kick_) kick_();
  batch->finish_if_done();
  return Exception::none;
}

void Device::command(Command c, modbus::WriteDone done, TimePoint now) {
  const std::uint16_t value = static_cast<std::uint16_t>(c);
  const Exception e = apply(Table::holding, 0, std::span<const std::uint16_t>(&value, 1), done, now,
                            Origin::gateway);
  if (e != Exception::none) done(e);
}

}  // namespace drivegate
