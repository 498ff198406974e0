// What every driver keeps alike, so that a driver declares only what is its own: the points it
// publishes, their values, the common state, and the outcomes of its writes (write_ledger.h) that
// take_completions() hands to the gateway. A driver derives from DriverBase rather than Driver,
// fills these in, and overrides the protocol's part of Driver (traits, the line, the writes).
// Header-only and compiled into each plugin: the daemon sees Driver alone, so the plugin ABI is
// Driver's.
//
// DRIVEGATE_DRIVER_OVERRIDES declares, in a driver's class, the protocol's part every driver
// overrides (the line and the writes); a driver adds the optional overrides it has after it.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "drivegate/driver.h"
#include "drivegate/point.h"
#include "drivegate/write_ledger.h"

// The overrides every driver declares: traits, the line side, and the two halves of a write.
#define DRIVEGATE_DRIVER_OVERRIDES                                                 \
  [[nodiscard]] DriverTraits traits() const override;                              \
  std::optional<Exchange> next_exchange(TimePoint now) override;                   \
  [[nodiscard]] TimePoint wake_at() const override;                                \
  RxVerdict on_receive(ByteView rx, TimePoint now) override;                       \
  void on_no_reply(TimePoint now) override;                                        \
  void on_comm_lost(TimePoint now) override;                                       \
  [[nodiscard]] WriteCheck check(std::span<const WriteOp> request) const override; \
  WriteStatus apply(const WriteOp& op, Ticket t, TimePoint now) override

namespace drivegate {

class DriverBase : public Driver {
 public:
  [[nodiscard]] const std::vector<PointSpec>& points() const final { return points_; }
  [[nodiscard]] const std::vector<Value>& values() const final { return values_; }
  [[nodiscard]] const CommonState& common() const final { return common_; }
  void take_completions(std::vector<Completion>& out) final { completions_.take(out); }
  void take_notices(std::vector<std::string>& out) final {
    out.insert(out.end(), notices_.begin(), notices_.end());
    notices_.clear();
  }

 protected:
  DriverBase() = default;
  explicit DriverBase(std::vector<PointSpec> points)
      : points_(std::move(points)), values_(points_.size()) {}

  std::vector<PointSpec> points_;  // fixed once the driver is made
  std::vector<Value> values_;      // points_'s, same order and size
  CommonState common_;
  Completions completions_;
  std::vector<std::string> notices_;  // for take_notices(), oldest first
};

// The status apply() answers for a part its driver's judgement (check()'s, now) would not take:
// nothing when it would.
constexpr std::optional<WriteStatus> refusal(WriteCheck c) {
  switch (c) {
    case WriteCheck::ok:
      return std::nullopt;
    case WriteCheck::invalid_value:
      return WriteStatus::invalid_value;
    case WriteCheck::refused:
      return WriteStatus::refused;
  }
  return WriteStatus::invalid_value;
}

}  // namespace drivegate
