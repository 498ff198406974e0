// The device's options: the schema the gateway validates them against, and the values the driver
// and the simulator use.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

#include "drivegate/options.h"
#include "payloads.h"

namespace drivegate::unicla {

inline constexpr std::array<OptionSpec, 4> kOptionSchema = {{
    // "Byte order" is stated by example only (speed 1000 = 03 E8) and not at all for floats.
    {"byte_order", OptionType::string, "big",
     "order of the float fields in read payloads (integers are big-endian per the document's "
     "example)",
     0, 0, "big|little"},
    // Not in the document: the longest read reply (Build Information, 92 characters) takes 48 ms
    // at 19200 baud, and 100 ms leaves the drive 50 ms to start answering.
    {"reply_timeout_ms", OptionType::integer, "100",
     "per-attempt wait for a read reply (an 80-byte reply takes about 50 ms at 19200 baud)", 20,
     2000},
    {"retries", OptionType::integer, "2", "identical resends of a read after no or a bad reply", 0,
     5},
    // "Write commands are not acknowledged ... success/fail can be determined by other means".
    {"confirm_timeout_ms", OptionType::integer, "2000",
     "how long a write waits for a status read that confirms it (writes are not acknowledged)", 200,
     10000},
}};

struct Settings {
  ByteOrder byte_order = ByteOrder::big;
  std::chrono::milliseconds reply_timeout{100};
  std::uint8_t attempts = 3;  // 1 + retries
  std::chrono::milliseconds confirm_timeout{2000};
};

// The options as the driver and the simulator use them. The schema has checked every value
// (defaults filled in) and no two options contradict each other; nullopt with `error` naming the
// option is kept for a value the schema let through that the protocol cannot carry.
std::optional<Settings> parse_settings(const Options& options, std::string& error);

}  // namespace drivegate::unicla
