#include "point_writes.h"

#include <fmt/format.h>
#include <pwd.h>
#include <unistd.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <functional>
#include <iostream>

#include "app/logging.h"
#include "config/port_address.h"
#include "gateway/gateway.h"
#include "gateway/value_codec.h"
#include "modbus/modbus_exception.h"
#include "transport/port_lock.h"

namespace drivegate::cli {

namespace asio = boost::asio;

namespace {

std::optional<double> parse_number(const std::string& s) {
  try {
    std::size_t used = 0;
    const double v = std::stod(s, &used);
    if (used == s.size()) return v;
  } catch (const std::exception&) {
  }
  return std::nullopt;
}

// What came of a write, for the operator.
const char* what(Outcome o) {
  switch (o) {
    case Outcome::ok:
      return "ok";
    case Outcome::no_such_device:
      return "no such device";
    case Outcome::no_such_point:
      return "not a writable point";
    case Outcome::denied:
      return "beyond the access level";
    case Outcome::invalid_value:
      return "value refused";
    case Outcome::busy:
      return "the device is busy";
    case Outcome::refused:
      return "the device refused it";
    case Outcome::no_response:
      return "the device did not confirm it in time";
  }
  return "failed";
}

// A failure with the Modbus exception a PLC's same write gets, which the adapters' documents
// speak of.
std::string outcome_text(Outcome o) {
  if (o == Outcome::ok) return what(o);
  return fmt::format("{} (0x{:02X})", what(o), static_cast<unsigned>(modbus_exception(o)));
}

// The current text of a string point of the device, if it has it.
std::string string_value(const Device& device, const std::string& point) {
  const MappedPoint* p = device.map().find(point);
  const auto& values = device.driver().values();
  if (p == nullptr || p->common() || p->index >= values.size()) return {};
  const auto* s = std::get_if<std::string>(&values[p->index]);
  return s != nullptr ? *s : std::string();
}

struct Resolved {
  const MappedPoint* point;
  std::vector<std::uint16_t> registers;
};

// Every assignment resolved to a point and its registers, before anything is sent.
std::optional<std::vector<Resolved>> resolve(const Device& device,
                                             const std::vector<Assignment>& writes) {
  std::vector<Resolved> out;
  for (const auto& w : writes) {
    const MappedPoint* point = device.map().find(w.point);
    if (point == nullptr || point->spec.access() != Access::read_write) {
      std::cerr << "drivegate: " << device.name() << " has no writable point '" << w.point << "'\n";
      return std::nullopt;
    }
    std::optional<double> v = parse_number(w.value);
    for (const auto& l : point->spec.labels) {
      if (l.name == w.value) v = l.value;
    }
    if (!v) {
      std::cerr << "drivegate: " << w.point << ": '" << w.value << "' is not a number"
                << (point->spec.labels.empty() ? "" : " or a label of the point") << "\n";
      return std::nullopt;
    }
    std::vector<std::uint16_t> regs(point->spec.register_count(), 0);
    encode_value(point->spec, Value{*v}, regs);
    out.push_back({point, std::move(regs)});
  }
  return out;
}

// Who runs the tool, for the audit trail: the login name, else the user id.
std::string console_user() {
  if (const struct passwd* pw = ::getpwuid(::getuid())) return pw->pw_name;
  return "uid " + std::to_string(::getuid());
}

}  // namespace

int run_point_writes(const PointWriteJob& job) {
  Config cfg = *job.config;
  std::erase_if(cfg.devices, [&](const DeviceConfig& d) { return d.name != job.device; });
  if (cfg.devices.empty()) {
    std::cerr << "drivegate: no device '" << job.device << "' in " << cfg.path.string() << "\n";
    return 1;
  }
  std::erase_if(cfg.buses, [&](const BusConfig& b) { return b.name != cfg.devices[0].bus; });
  // The line is the daemon's while it runs: say so now, rather than time out on a shared line.
  // Held until the writes are done; the bus below finds it ours.
  PortLock lock;
  std::string ignored;
  const auto address =
      cfg.buses.empty() ? std::nullopt : parse_port_address(cfg.buses[0].port, ignored);
  if (address && !address->network()) {
    if (lock.acquire(address->path) == PortError::in_use) {
      std::cerr << "drivegate: " << cfg.buses[0].port << " is in use by " << lock.owner()
                << ": stop it first (systemctl stop drivegate)\n";
      return 1;
    }
  }

  asio::io_context io;
  auto log = make_logger("drivegate", spdlog::level::warn);
  std::vector<std::string> errors;
  // Each write is audited like the daemon's (history/command_audit.h), into the journal: the
  // daemon, whose history would keep it, is stopped.
  // Where journald cannot be reached, the record goes to stderr: never lost in silence.
  const auto journal =
      make_journal_writer(make_logger("drivegate", spdlog::level::info), /*always_journal=*/true);
  History history(kDefaultHistory, &EventLog::system_ms, journal.get());
  auto gateway = Gateway::build(io, cfg, *job.plugins, log, errors, /*maintenance=*/true, &history);
  for (const auto& e : errors) std::cerr << e << "\n";
  if (!gateway) return 1;
  Device& device = *gateway->devices().front();
  const auto resolved = resolve(device, job.writes);
  if (!resolved) return 1;

  int exit_code = 0;
  std::size_t next = 0;
  asio::steady_timer timer(io);
  const auto deadline = Clock::now() + job.timeout;
  std::function<void()> step = [&] {
    if (next == resolved->size()) {
      gateway->stop();
      return;
    }
    const Resolved& r = (*resolved)[next];
    const auto done = [&](Outcome outcome) {
      const Assignment& w = job.writes[next];
      std::cout << w.point << "=" << w.value << ": " << outcome_text(outcome);
      if (outcome != Outcome::ok && !job.message_point.empty()) {
        if (const auto why = string_value(device, job.message_point); !why.empty()) {
          std::cout << ": " << why;
        }
      }
      std::cout << std::endl;
      if (outcome != Outcome::ok) {
        exit_code = 1;
        gateway->stop();
        return;
      }
      ++next;
      asio::post(io, step);
    };
    // The operator at the console, with the configuration file in hand: every writable point, in
    // the register map's word order (the values were encoded in it).
    Session console{AccessLevel::maintain, WordOrder::big, true};
    console.source.kind = SourceKind::cli;
    console.source.client = console_user();
    const Outcome at_once = device.write(console, r.point->spec.table, r.point->address,
                                         r.registers, done, Clock::now());
    if (at_once != Outcome::ok) done(at_once);
  };
  std::function<void()> wait_online = [&] {
    if (device.online()) {
      step();
      return;
    }
    if (Clock::now() > deadline) {
      std::cerr << "drivegate: " << job.device << " did not come online within "
                << job.timeout.count() << " ms\n";
      exit_code = 1;
      gateway->stop();
      return;
    }
    timer.expires_after(Millis(50));
    timer.async_wait([&](const boost::system::error_code& ec) {
      if (!ec) wait_online();
    });
  };
  gateway->start();
  wait_online();
  io.run();
  return exit_code;
}

}  // namespace drivegate::cli
