#include "line_config.h"

#include <algorithm>
#include <array>

#include "port_address.h"

namespace drivegate {

namespace {

constexpr std::array<std::uint32_t, 12> kBauds = {300,   600,   1200,  2400,   4800,   9600,
                                                  19200, 38400, 57600, 115200, 230400, 460800};

}  // namespace

LineGiven read_line(TableReader& r, const std::string& prefix, BusConfig& bus, Diagnostics& diag) {
  std::optional<PortAddress> address;
  if (auto port = r.string("port", true)) {
    bus.port = *port;
    std::string error;
    address = parse_port_address(*port, error);
    if (!address) diag.error(r.node("port"), prefix + ".port", error);
  }
  if (auto v = r.integer("network_delay_ms", 0, 10'000, false)) {
    bus.network_delay = Millis(*v);
  }
  if (auto v = r.integer("baud", 1, 4'000'000, false)) {
    if (std::find(kBauds.begin(), kBauds.end(), *v) == kBauds.end()) {
      diag.error(r.node("baud"), prefix + ".baud",
                 "not a standard rate (300, 600, 1200, 2400, 4800, 9600, 19200, 38400, "
                 "57600, 115200, 230400, 460800)");
    } else {
      bus.baud = static_cast<std::uint32_t>(*v);
    }
  }
  if (auto p = r.string("parity", false)) {
    if (auto parity = parse_parity(*p)) {
      bus.parity = *parity;
    } else {
      diag.error(r.node("parity"), prefix + ".parity", "must be none, even or odd");
    }
  }
  LineGiven g;
  g.baud = r.node("baud") != nullptr;
  g.parity = r.node("parity") != nullptr;
  if (auto v = r.integer("data_bits", 5, 8, false)) bus.data_bits = static_cast<std::uint8_t>(*v);
  if (auto v = r.integer("stop_bits", 1, 2, false)) bus.stop_bits = static_cast<std::uint8_t>(*v);
  g.data_bits = r.node("data_bits") != nullptr;
  g.stop_bits = r.node("stop_bits") != nullptr;
  const auto echo = r.boolean("echo");
  bus.echo = echo.value_or(false);
  g.echo = echo.has_value();
  bus.rs485 = r.boolean("rs485").value_or(false);
  if (bus.rs485 && address && address->network()) {
    diag.error(r.node("rs485"), prefix + ".rs485",
               "applies to a local serial port only (a device server drives its own RS-485 "
               "transceiver)");
  }
  if (auto v = r.integer("reopen_max_ms", 100, 600'000, false)) bus.reopen_max = Millis(*v);
  return g;
}

}  // namespace drivegate
