#include "scan_report.h"

#include <algorithm>
#include <cctype>
#include <cstdio>

#include "modbus/backend.h"

namespace drivegate::cli {

namespace md = modbus_device;

namespace {

std::string hex2(std::uint8_t b) {
  char out[3];
  std::snprintf(out, sizeof out, "%02X", b);
  return out;
}

// A device's string as it may be shown in a terminal: printable ASCII as it is (quote and
// backslash escaped), anything else as \xNN, in double quotes.
std::string shown(std::string_view s) {
  std::string out = "\"";
  for (const char c : s) {
    const auto b = static_cast<std::uint8_t>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (b >= 0x20 && b < 0x7F) {
      out += c;
    } else {
      out += "\\x" + hex2(b);
    }
  }
  return out + "\"";
}

// A TOML basic string.
std::string toml_string(std::string_view s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

std::string exception_text(std::uint8_t code) {
  return "exception " + hex2(code) + " (" +
         std::string(modbus::to_string(static_cast<modbus::Exception>(code))) + ")";
}

// What the slave answered the probe (scan.h: a read of holding register 0) with.
std::string probe_text(const md::FoundSlave& s) {
  const Bytes& pdu = s.probe_reply;
  std::string out;
  if (const auto code = md::exception_code(pdu)) {
    out = exception_text(*code) + " to a read of holding register 0";
  } else if (pdu.size() == 4 && pdu[0] == md::fc::read_holding_registers && pdu[1] == 2) {
    out = "holding register 0 = " + std::to_string(be16(pdu[2], pdu[3]));
  } else if (pdu.size() >= 2 && pdu[0] == md::fc::read_holding_registers) {
    // Application Protocol 6.3: one register read is answered with a byte count of 2.
    out = "a read of holding register 0 answered with byte count " + std::to_string(pdu[1]) +
          " and " + std::to_string(pdu.size() - 2) + " bytes, not the 2 of one register";
  } else {
    out = "a reply of function 0x" + hex2(pdu.empty() ? 0 : pdu[0]);
  }
  return s.late ? out + ", late" : out;
}

std::string identity_text(const md::FoundSlave& s) {
  switch (s.identity_status) {
    case md::Identity::pending:
      return "identification not asked";
    case md::Identity::refused:
      return "no identification: " + exception_text(s.identity_exception);
    case md::Identity::no_reply:
      return "no identification: no reply";
    case md::Identity::bad_reply:
      return "no identification: a reply that is not one";
    case md::Identity::given:
      break;
  }
  if (s.identity.empty()) return "identification without objects";
  std::string out;
  for (const auto& o : s.identity) {
    const auto name = md::device_id_object_name(o.id);
    out += (out.empty() ? "" : ", ") +
           (name.empty() ? "object 0x" + hex2(o.id) : std::string(name)) + " " + shown(o.value);
  }
  return out;
}

// "8E1": data bits, parity, stop bits, as a line's settings are usually written.
std::string line_text(const BusConfig& line, md::Framing framing) {
  const char parity = line.parity == Parity::none ? 'N' : line.parity == Parity::even ? 'E' : 'O';
  return std::to_string(line.baud) + " baud " + std::to_string(line.data_bits) + parity +
         std::to_string(line.stop_bits) + ", " +
         std::string(md::kFramingNames[static_cast<std::size_t>(framing)]);
}

std::string address_list(std::span<const std::uint8_t> addresses) {
  std::string out;
  for (const auto a : addresses) out += (out.empty() ? "" : ", ") + std::to_string(a);
  return out;
}

// The bus's name in the snippet: the tty's own ("ttyUSB0"), or "line" for a device server.
std::string bus_name(const std::string& port) {
  std::string name;
  if (!port.empty() && port.front() == '/') {
    for (const char c : port.substr(port.rfind('/') + 1)) {
      if (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.') {
        name += c;
      }
    }
  }
  return name.empty() ? "line" : name.substr(0, 48);
}

// Where a profile for a slave no profile matches could be written: named after its product
// code where it gave one (a profile's name is a-z, 0-9, '-', '_'), else after its address.
std::string profile_to_write(const md::FoundSlave& s) {
  std::string name;
  for (const char c : std::string(s.object(md::device_id_object::product_code).value_or(""))) {
    const char l = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    const bool ok = (l >= 'a' && l <= 'z') || (l >= '0' && l <= '9') || l == '_';
    if (ok) {
      name += l;
    } else if (!name.empty() && name.back() != '-') {
      name += '-';
    }
  }
  while (!name.empty() && name.back() == '-') name.pop_back();
  if (name.empty()) name = "slave-" + std::to_string(s.address);
  return "/etc/drivegate/profiles/" + name.substr(0, 64) + ".toml";
}

std::string snippet(const ScanReport& r, const std::vector<const md::FoundSlave*>& slaves) {
  const std::string bus = bus_name(r.line.port);
  std::string out =
      "# drivegate.toml for what was found (docs/profiles.md); each unit_id is the slave's "
      "address\n"
      "[[bus]]\nname = " +
      toml_string(bus) + "\nport = " + toml_string(r.line.port) +
      "\nbaud = " + std::to_string(r.line.baud) +
      "\nparity = " + toml_string(to_string(r.line.parity)) +
      "\ndata_bits = " + std::to_string(r.line.data_bits) +
      "\nstop_bits = " + std::to_string(r.line.stop_bits) + "\n";
  if (r.line.rs485) out += "rs485 = true\n";
  if (r.scanner->echoes() > 0) out += "echo = true  # the line gives back what is sent\n";
  for (const md::FoundSlave* s : slaves) {
    const std::string address = std::to_string(s->address);
    out += "\n[[device]]\nname = " + toml_string(bus + "-" + address) +
           "\nbus = " + toml_string(bus) + "\nadapter = \"modbus\"\nunit_id = " + address +
           "\naddress = " + address + "\n[device.options]\n";
    const auto matches = matching_profiles(*s, r.profiles);
    if (matches.empty()) {
      out +=
          "# no profile matches it: write one (docs/profiles.md) and name it here\n"
          "profile = " +
          toml_string(profile_to_write(*s)) + "\n";
      continue;
    }
    out += "profile = " + toml_string(matches.front()->reference) + "\n";
    for (std::size_t i = 1; i < matches.size(); ++i) {
      out += "# also matches: profile = " + toml_string(matches[i]->reference) + "\n";
    }
  }
  return out;
}

}  // namespace

std::vector<const KnownProfile*> matching_profiles(const md::FoundSlave& slave,
                                                   std::span<const KnownProfile> profiles) {
  std::vector<const KnownProfile*> out;
  const auto vendor = slave.object(md::device_id_object::vendor_name);
  const auto product = slave.object(md::device_id_object::product_code);
  if (!vendor || !product) return out;
  for (const KnownProfile& p : profiles) {
    if (md::identifies(p.identification, *vendor, *product)) out.push_back(&p);
  }
  return out;
}

std::string slave_line(const md::FoundSlave& slave, std::span<const KnownProfile> profiles) {
  std::string out = "address " + std::to_string(slave.address) + ": " + probe_text(slave) + "; " +
                    identity_text(slave) + "; ";
  const auto matches = matching_profiles(slave, profiles);
  if (matches.empty()) {
    const bool identified = slave.object(md::device_id_object::vendor_name) &&
                            slave.object(md::device_id_object::product_code);
    return out +
           (identified ? "no profile matches"
                       : "no profile suggested without "
                         "VendorName and ProductCode") +
           "\n";
  }
  out += matches.size() == 1 ? "profile " : "profiles ";
  for (const KnownProfile* p : matches) {
    out += (p == matches.front() ? "" : ", ") + p->reference;
  }
  return out + "\n";
}

std::string scan_report(const ScanReport& r) {
  const md::Scanner& scan = *r.scanner;
  std::vector<const md::FoundSlave*> slaves;
  for (const auto& s : scan.found()) slaves.push_back(&s);
  std::sort(slaves.begin(), slaves.end(), [](const md::FoundSlave* a, const md::FoundSlave* b) {
    return a->address < b->address;
  });
  std::string out;
  for (const md::FoundSlave* s : slaves) out += slave_line(*s, r.profiles);
  const std::size_t n = slaves.size();
  out += (n == 0 ? std::string("no slave") : std::to_string(n) + (n == 1 ? " slave" : " slaves")) +
         " found on " + r.line.port + " (" + line_text(r.line, r.framing) + "), addresses " +
         r.addresses;
  if (r.interrupted) {
    out += ": interrupted after " + std::to_string(scan.probed()) + " of " +
           std::to_string(scan.total());
  }
  out += "\n";
  std::vector<std::uint8_t> late;
  for (const md::FoundSlave* s : slaves) {
    if (s->late) late.push_back(s->address);
  }
  if (!late.empty()) {
    out += "note: address " + address_list(late) +
           " answered after its wait (found all the same): a longer --timeout-ms suits it\n";
  }
  if (!scan.garbled().empty()) {
    out += "note: bytes that made no good frame came at address " + address_list(scan.garbled()) +
           ": another baud rate, parity or framing on the line, two slaves at one address, or a "
           "reply cut short or whose byte count says more than it carries\n";
  }
  if (scan.foreign_frames() > 0) {
    out += "note: " + std::to_string(scan.foreign_frames()) +
           " good frames came from addresses not asked: is another master on the line?\n";
  }
  if (scan.echoes() > 0) {
    out += "note: the line gives back every request as it is sent: its bus needs echo = true\n";
  }
  if (!slaves.empty()) out += "\n" + snippet(r, slaves);
  return out;
}

}  // namespace drivegate::cli
