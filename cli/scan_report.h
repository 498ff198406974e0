// What `drivegate scan` prints on stdout once the scan is over, pure: one line per slave found,
// a summary line, notes on what looked wrong on the line, and the configuration for what was
// found ([[bus]] and a [[device]] per slave, with the profile suggested where one matches).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "config/config.h"
#include "scan.h"

namespace drivegate::cli {

// A profile `drivegate scan` may suggest: one that says which identification it is for.
struct KnownProfile {
  std::string reference;  // as [device.options] profile names it: its name, or its file's path
  modbus_device::ProfileIdentification identification;
};

// The profiles whose identification `slave`'s matches (modbus_device::identifies), in the order
// given; none for a slave that gave no VendorName and ProductCode.
std::vector<const KnownProfile*> matching_profiles(const modbus_device::FoundSlave& slave,
                                                   std::span<const KnownProfile> profiles);

struct ScanReport {
  BusConfig line;  // port, baud, parity, data and stop bits, rs485 as scanned
  modbus_device::Framing framing = modbus_device::Framing::rtu;
  std::string addresses;  // as given: "1-247"
  const modbus_device::Scanner* scanner = nullptr;
  std::span<const KnownProfile> profiles;
  bool interrupted = false;  // stopped before the last address (the summary says where)
};

// "17: registers (holding 0 = 0x0006); VendorName "..." ...; profile example" for one slave.
std::string slave_line(const modbus_device::FoundSlave& slave,
                       std::span<const KnownProfile> profiles);
// Everything: the slaves by address, the summary, the notes and, when a slave was found, the
// configuration snippet after a blank line.
std::string scan_report(const ScanReport& report);

}  // namespace drivegate::cli
