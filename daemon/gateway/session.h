// Who asks the gateway for a read or a write: the access level and word order of a Modbus
// connection (its listener's, or its TLS client certificate's role) or of the MQTT commands, and
// who the client is (source.h).
// Every northbound makes one; the gateway judges each request by it.
//
// Header-only, in the CMake target dg_gateway_api, which sits below dg_modbus: the Modbus
// listeners carry a session for every connection and the configuration names access levels and
// word orders, and neither links the gateway for it. What the gateway answers is outcome.h.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string_view>

#include "gateway/fault_reads.h"
#include "gateway/source.h"

namespace drivegate {

// What a client may do (README, "Listeners and access"). Ordered: each level includes the ones
// below it.
enum class AccessLevel : std::uint8_t {
  read,      // reads only: every write is denied
  operate,   // also the common command block: command, setpoint_rpm, heartbeat
  maintain,  // every writable point
};

// Their names in drivegate.toml and in the log, in enum order.
inline constexpr std::array<std::string_view, 3> kAccessLevelNames = {"read", "operate",
                                                                      "maintain"};
constexpr std::string_view to_string(AccessLevel a) {
  return kAccessLevelNames.at(static_cast<std::size_t>(a));
}

// How 32- and 64-bit values are laid over their registers for a client: big = most significant
// word first (the register map's order), little = least significant first. Registers of 16 bits,
// strings and bits are never reordered.
enum class WordOrder : std::uint8_t { big, little };
inline constexpr std::array<std::string_view, 2> kWordOrderNames = {"big", "little"};
constexpr std::string_view to_string(WordOrder w) {
  return kWordOrderNames.at(static_cast<std::size_t>(w));
}

// Passed with every read and write. The default may only read: a session gets more only from its
// listener, its certificate or the MQTT configuration.
struct Session {
  AccessLevel access = AccessLevel::read;
  WordOrder word_order = WordOrder::big;
  // Whether this client's valid writes to the command block prove the PLC is there (feed the
  // PLC-loss failsafe, docs/safety.md). Every Modbus client's do; MQTT's only when configured.
  bool feeds_failsafe = true;
  // Who it is, for the audit trail (source.h).
  Source source{};
  // What this client has read of each drive's faults (fault_reads.h): its connection's own, kept
  // across its requests; none where the northbound cannot tell (MQTT) or for the gateway's own.
  std::shared_ptr<FaultReads> fault_reads{};
};

}  // namespace drivegate
