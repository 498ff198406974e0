// The adapter's device options: schema and the parsed form the driver and simulator use.
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
    {"byte_order", OptionType::string, "big",
     "order of the float fields in read payloads (integers are big-endian per the document's "
     "example)",
     0, 0, "big|little"},
    {"reply_timeout_ms", OptionType::integer, "100",
     "per-attempt wait for a read reply (an 80-byte reply takes about 50 ms at 19200 baud)", 20,
     2000},
    {"retries", OptionType::integer, "2", "identical resends of a read after no or a bad reply", 0,
     5},
    {"confirm_timeout_ms", OptionType::integer, "2000",
     "how long a write waits for a status read that confirms it (writes are not acknowledged)", 200,
     10000},
}};

struct Settings {
  ByteOrder byte_order = ByteOrder::big;
  std::chrono::milliseconds reply_timeout{100};
  std::uint8_t attempts = 3;
  std::chrono::milliseconds confirm_timeout{2000};
};

// Options missing from `o` take the schema's default; nullopt with `error` set when a value
// is outside the schema.
std::optional<Settings> parse_settings(const Options& o, std::string& error);

}  // namespace drivegate::unicla
