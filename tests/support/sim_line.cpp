#include "sim_line.h"

#include <algorithm>

namespace drivegate::test {

namespace {
constexpr Millis kSimTick{10};  // Simulator::on_tick() is to be called at least every 50 ms
}  // namespace

void SimLine::start() {
  if (ticking_) return;
  ticking_ = true;
  clock_.at(clock_.now() + kSimTick, [this] { tick(); });
}

void SimLine::send(ByteView frame) {
  // The kernel takes the bytes at once; they leave the UART after what is still leaving it, over
  // the frame's time on the wire.
  const TimePoint start = std::max(clock_.now(), uart_free_);
  Bytes bytes(frame.begin(), frame.end());
  sent.push_back({start, bytes});
  clock_.at(clock_.now(), [this] { engine_->on_sent(); });
  const TimePoint end = start + on_wire(bytes.size());
  uart_free_ = end;
  if (echo_) {
    clock_.at(end, [this, bytes] { engine_->on_received(bytes); });
  }
  if (!connected) return;
  clock_.at(end, [this, bytes] {
    Bytes answer;
    for (Simulator* sim : sims_) {
      const Bytes r = sim->on_receive(bytes, clock_.now());
      answer.insert(answer.end(), r.begin(), r.end());
    }
    if (!answer.empty()) from_devices(std::move(answer), clock_.now() + turnaround);
  });
}

void SimLine::from_devices(Bytes bytes, TimePoint start) {
  answers.push_back({start, bytes});
  if (device_filter) bytes = device_filter(std::move(bytes));
  if (bytes.empty()) return;
  const TimePoint arrival = start + on_wire(bytes.size());
  clock_.at(arrival, [this, bytes = std::move(bytes)] { engine_->on_received(bytes); });
}

void SimLine::tick() {
  const TimePoint now = clock_.now();
  for (Simulator* sim : sims_) {
    Bytes unsolicited = sim->on_tick(now);
    if (!unsolicited.empty() && connected) from_devices(std::move(unsolicited), now);
  }
  clock_.at(now + kSimTick, [this] { tick(); });
}

}  // namespace drivegate::test
