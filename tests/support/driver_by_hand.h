// A driver alone, made by the adapter's own factory (adapter_factories.h), with no engine and no
// line: the device's side is played by hand, so that a test can put the driver into any state,
// call it directly and see each call's effect. An adapter's contract tests derive from it and
// answer its frames as the device would (turn()); write_contract.h runs the checks every adapter
// owes on top of it.
#pragma once

#include <chrono>
#include <memory>
#include <optional>
#include <vector>

#include "drivegate/driver.h"

namespace drivegate::test {

class DriverByHand {
 public:
  explicit DriverByHand(std::unique_ptr<Driver> driver) : d(std::move(driver)) {}
  DriverByHand(const DriverByHand&) = delete;
  DriverByHand& operator=(const DriverByHand&) = delete;
  virtual ~DriverByHand() = default;

  // One turn of the line as the device plays it: the exchange the driver wants now, recorded in
  // `sent` and answered, or time let pass when it wants none. False when nothing more can come.
  virtual bool turn() = 0;

  // Applies one part of a request with the next ticket, as the gateway does.
  WriteStatus apply(const WriteOp& op) { return d->apply(op, ++ticket, now); }
  // Turns the line until the part applied with ticket `t` completed (at most `turns` turns); its
  // result, nothing if it never did.
  std::optional<WriteResult> settle(Ticket t, int turns = 100);
  // The completions since the last call, but for those settle() took.
  std::vector<Completion> completions();

  std::unique_ptr<Driver> d;
  TimePoint now = TimePoint{} + std::chrono::hours(1);
  Ticket ticket = 0;
  std::vector<Bytes> sent;  // every frame the driver sent, in order

 private:
  std::vector<Completion> done_;
};

}  // namespace drivegate::test
