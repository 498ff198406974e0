// Fuzz target body shared by every adapter. Input: a mode byte, then a script for that mode.
//   mode % 3 == 0: the codec's incremental decoders over the rest (adapters/<id>/fuzz/codec_fuzz.cpp)
//   mode % 3 == 1: a Driver, created through the plugin descriptor with its default options and
//                  driven like the bus engine drives it (daemon/bus/bus_engine.cpp): receive
//                  chunks, the time, and commands, setpoints and point writes validated as the
//                  device does (daemon/gateway/device_writes.cpp), judged by check() first
//   mode % 3 == 2: a Simulator: master bytes in chunks, ticks, operator control lines
#include "adapter_fuzz.h"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "check.h"
#include "plugin/adapter_options.h"
#include "drivegate/adapter.h"
#include "gateway/value_codec.h"

extern "C" const drivegate::AdapterDescriptor drivegate_adapter;

namespace drivegate::fuzz {
namespace {

// daemon/bus/bus_engine.cpp: an incomplete reply longer than this is dropped as noise.
constexpr std::size_t kMaxRxBuffer = 4096;

std::uint32_t pick_address(const AdapterDescriptor& a, std::uint8_t choice) {
  if (choice < 0x80 || a.address_max <= a.address_min) return a.default_address;
  return a.address_min + choice % (a.address_max - a.address_min + 1);
}

// Every value the driver publishes must encode into registers, as the register image does.
void check_published(const Driver& d) {
  const auto& points = d.points();
  const auto& values = d.values();
  FUZZ_CHECK(values.size() == points.size());
  std::vector<std::uint16_t> regs;
  for (std::size_t i = 0; i < points.size(); ++i) {
    regs.assign(points[i].register_count(), 0);
    encode_value(points[i], values[i], regs);
  }
  const CommonState& c = d.common();
  (void)c.faults.bits();
  (void)d.wake_at();
}

class DriverRun {
 public:
  DriverRun(Driver& driver, TimePoint start) : d_(driver), now_(start) {}

  void step(FuzzInput& in) {
    switch (in.u8() % 10) {
      case 0:
        if (auto ex = d_.next_exchange(now_)) awaiting_ = ex->reply == ReplyMode::expected;
        break;
      case 1: {
        const auto chunk = in.bytes(in.u8());
        rx_.insert(rx_.end(), chunk.begin(), chunk.end());
        process_rx();
        break;
      }
      case 2:
        now_ += Millis(in.u16());
        break;
      case 3:
        submit(WriteOp::of_command(static_cast<Command>(in.u8() % kAllCommands.size())));
        break;
      case 4:
        // The common block's setpoint_rpm register is i16 (docs/register-map.md).
        submit(WriteOp::of_setpoint(static_cast<std::int16_t>(in.u16())));
        break;
      case 5:
        write_point(in);
        break;
      case 6:
        d_.on_no_reply(now_);
        awaiting_ = false;
        break;
      case 7:
        d_.on_comm_lost(now_);
        break;
      case 8:
        take_completions();
        break;
      default: {
        // A "run at this speed" request, judged only: check() must not change anything.
        const WriteOp request[] = {WriteOp::of_setpoint(static_cast<std::int16_t>(in.u16())),
                                   WriteOp::of_command(Command::run_forward)};
        (void)d_.check(request);
        (void)d_.traits();
        break;
      }
    }
    check_published(d_);
  }

  void take_completions() {
    std::vector<Completion> done;
    d_.take_completions(done);
    for (const Completion& c : done) {
      // Driver contract (driver.h): one Completion per ticket answered `pending`.
      const auto it = pending_.find(c.ticket);
      FUZZ_CHECK(it != pending_.end());
      pending_.erase(it);
    }
  }

 private:
  // As the device applies a one-part request: judged first, applied only when accepted.
  void submit(const WriteOp& op) {
    if (d_.check(std::span<const WriteOp>(&op, 1)) != WriteCheck::ok) return;
    const WriteStatus s = d_.apply(op, ++ticket_, now_);
    // Driver contract (driver.h): what check() accepts, apply() takes in the same state.
    FUZZ_CHECK(s == WriteStatus::done || s == WriteStatus::pending);
    if (s == WriteStatus::pending) pending_.emplace(ticket_, true);
  }

  // The bus engine's receive loop (Bus::process_rx): verdicts drop at least one byte.
  void process_rx() {
    while (!rx_.empty()) {
      const RxVerdict v = d_.on_receive(rx_, now_);
      if (v.kind == RxKind::incomplete) {
        if (rx_.size() > kMaxRxBuffer) rx_.clear();
        break;
      }
      const std::size_t used = std::clamp<std::size_t>(v.consumed, 1, rx_.size());
      rx_.erase(rx_.begin(), rx_.begin() + static_cast<std::ptrdiff_t>(used));
      if (v.kind == RxKind::reply || v.kind == RxKind::ack) awaiting_ = false;
    }
  }

  // A client's write as Device::validate lets it through: a writable point, a value its type
  // decodes, inside the point's min / max when it has one.
  void write_point(FuzzInput& in) {
    const auto& points = d_.points();
    if (points.empty()) return;
    const std::size_t index = in.u8() % points.size();
    const PointSpec& p = points[index];
    if (p.access() != Access::read_write) return;
    Value v;
    if (p.table == Table::coil) {
      v = std::int64_t{in.u8() & 1};
    } else {
      std::vector<std::uint16_t> regs(p.register_count());
      for (auto& r : regs) r = in.u16();
      auto decoded = decode_value(p, regs);
      if (!decoded) return;
      v = std::move(*decoded);
      const double x = as_double(v);
      if ((p.min != 0.0 || p.max != 0.0) && (x < p.min || x > p.max)) return;
    }
    submit(WriteOp::of_point(index, std::move(v)));
  }

  Driver& d_;
  TimePoint now_;
  Bytes rx_;
  bool awaiting_ = false;
  Ticket ticket_ = 0;
  std::map<Ticket, bool> pending_;
};

// The options a device is made with: the defaults, and for an adapter whose devices follow a
// description they name (AdapterDescriptor::specialise) its demo's, which name one.
Options options_of(const AdapterDescriptor& a) {
  Options options = default_options(a);
  if (a.specialise == nullptr) return options;
  for (std::size_t i = 0; i < a.demo.option_count; ++i) {
    std::string error;
    (void)set_option_text(a, options, a.demo.options[i].name, a.demo.options[i].value, error);
  }
  return options;
}

void fuzz_driver(const AdapterDescriptor& a, FuzzInput& in) {
  DeviceEnv env;
  env.name = "fuzz";
  env.address = pick_address(a, in.u8());
  env.poll_interval = Millis(50 + 10 * in.u8());
  env.options = options_of(a);
  env.maintenance = (in.u8() & 1) != 0;
  std::string error;
  auto driver = a.create_driver(env, error);
  if (!driver) return;
  check_published(*driver);
  DriverRun run(*driver, TimePoint{} + std::chrono::hours(1));
  while (!in.empty()) run.step(in);
  run.take_completions();
}

void fuzz_simulator(const AdapterDescriptor& a, FuzzInput& in) {
  SimEnv env;
  env.address = pick_address(a, in.u8());
  env.options = options_of(a);
  std::string error;
  auto sim = a.create_simulator(env, error);
  if (!sim) return;
  TimePoint now = TimePoint{} + std::chrono::hours(1);
  while (!in.empty()) {
    switch (in.u8() % 4) {
      case 0:
      case 1:
        (void)sim->on_receive(in.bytes(in.u8()), now);
        break;
      case 2:
        now += Millis(in.u16());
        (void)sim->on_tick(now);
        break;
      default: {
        const auto text = in.bytes(in.u8() % 64);
        (void)sim->control(std::string(text.begin(), text.end()), now);
        break;
      }
    }
  }
}

}  // namespace
}  // namespace drivegate::fuzz

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  drivegate::fuzz::FuzzInput in(data, size);
  switch (in.u8() % 3) {
    case 0:
      drivegate::fuzz::fuzz_codec(in);
      break;
    case 1:
      drivegate::fuzz::fuzz_driver(drivegate_adapter, in);
      break;
    default:
      drivegate::fuzz::fuzz_simulator(drivegate_adapter, in);
      break;
  }
  return 0;
}
