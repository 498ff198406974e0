#include "gateway/device.h"

namespace drivegate {

namespace {

LinkPolicy policy_of(const DeviceConfig& c, const AdapterDescriptor& a, const DriverTraits& t) {
  LinkPolicy p;
  p.poll_interval = c.poll_interval;
  p.budget = c.budget;
  p.backoff_max = c.backoff_max;
  p.comm_timeout = t.comm_timeout;
  p.inter_frame_gap = t.inter_frame_gap;
  p.streaming = a.streaming;
  return p;
}

}  // namespace

Device::Device(DeviceConfig config, const AdapterDescriptor& adapter,
               std::unique_ptr<Driver> driver, std::shared_ptr<spdlog::logger> log, TimePoint now,
               History* history)
    : config_(std::move(config)),
      adapter_(adapter),
      driver_(std::move(driver)),
      traits_(driver_->traits()),
      map_(driver_->points()),
      log_(std::move(log)),
      link_{policy_of(config_, adapter_, traits_),
            LinkHealth(now, traits_.state_in_parts),
            {},
            nullptr,
            log_},
      image_(map_),
      writes_(traits_.write_timeout),
      failsafe_(config_.failsafe.timeout),
      last_tick_(now),
      recorder_(history, config_.name, config_.unit_id) {
  refresh_image(now);
  refresh_common(Table::input, now);
  refresh_common(Table::discrete, now);
}

Device::~Device() = default;

bool Device::online() const {
  return link_.health.ever_good() && !link_.health.comm_lost() && driver_->common().ready;
}

// --- the engine's calls, each followed by publish() ---

std::optional<Exchange> Device::next_exchange(TimePoint now, Turn turn) {
  const bool applied = turn == Turn::write && release(now, true);
  writes_.exchanged();
  std::optional<Exchange> ex = driver_->next_exchange(now);
  // Choosing what to send changes no value a watcher reads; a part applied may have.
  publish(now, applied);
  return ex;
}

RxVerdict Device::on_receive(ByteView rx, TimePoint now) {
  const RxVerdict v = driver_->on_receive(rx, now);
  publish(now);
  return v;
}

void Device::on_no_reply(TimePoint now) {
  driver_->on_no_reply(now);
  publish(now);
}

void Device::on_comm_lost(TimePoint now) {
  driver_->on_comm_lost(now);
  publish(now);
  fail_pending(Outcome::no_response, now, "comm lost");
}

void Device::on_tick(TimePoint now) {
  last_tick_ = now;
  expire_requests(now);
  failsafe_tick(now);
  stop_on_start(now);
  record_changes();
}

// The first time the drive answers (daemon start, or the device added or changed by a reload),
// seen in the same call that brought it online, before any client's write: a drive found
// running is shown as it runs (the driver's contract), or stopped if on_start says so, on the
// next tick, unless a client has written to it meanwhile. A kept device never comes here again.
void Device::first_contact() {
  start_ = StartCheck::checked;
  const CommonState& s = driver_->common();
  if (!s.running) return;
  if (config_.on_start == StartAction::adopt) {
    log_->info(
        "device {}: found running ({}, setpoint {} rpm, speed {} rpm), shown as it runs "
        "(on_start = adopt)",
        config_.name, to_string(s.command), s.setpoint_rpm, s.speed_rpm);
    return;
  }
  log_->warn("device {}: found running (speed {} rpm): stopping it (on_start = stop)", config_.name,
             s.speed_rpm);
  start_ = StartCheck::stop_due;
}

void Device::stop_on_start(TimePoint now) {
  if (start_ != StartCheck::stop_due) return;
  start_ = StartCheck::checked;
  command(
      Command::stop,
      [this](Outcome outcome) {
        if (outcome == Outcome::ok) {
          log_->info("device {}: stop on start confirmed by the drive", config_.name);
        } else {
          log_->warn("device {}: stop on start not confirmed ({})", config_.name,
                     to_string(outcome));
        }
      },
      now, SourceKind::gateway);
}

// Settles the writes the driver completed (which may apply the next part of their request) and
// logs what changed. The image itself is refreshed when it is next read.
void Device::publish(TimePoint now, bool always) {
  image_.stale();
  std::vector<Completion> completions;
  driver_->take_completions(completions);
  const bool settled = !completions.empty();
  while (!completions.empty()) {
    for (const Completion& c : completions) settle(c, now);
    completions.clear();
    driver_->take_completions(completions);  // applying a next part may settle at once
  }
  std::vector<std::string> notices;
  driver_->take_notices(notices);
  for (const std::string& n : notices) log_->warn("device {}: {}", config_.name, n);
  log_changes();
  record_changes();
  if (watcher_ && (always || settled)) watcher_();
}

void Device::log_changes() {
  const bool on = online();
  if (on != logged_online_) {
    logged_online_ = on;
    if (on) log_->info("device {}: online", config_.name);
    if (on && start_ == StartCheck::unchecked) first_contact();
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

}  // namespace drivegate
