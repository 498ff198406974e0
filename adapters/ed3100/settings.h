// The device's options: the schema the gateway validates them against, and the values the driver
// and the simulator use.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "codec.h"
#include "drivegate/driver.h"
#include "drivegate/options.h"

namespace drivegate::ed3100 {

inline constexpr std::array<OptionSpec, 11> kOptionSchema = {{
    {"poles", OptionType::integer, "4", "motor poles: rpm = Hz x 120 / poles", 2, 64},
    {"monitors", OptionType::string_list, "0D00:Hz,0D01,0D02,0D03",
     "monitor registers 0D00..0D28 to poll and expose, each optionally with :V, :Hz or :A"},
    {"speed_monitor", OptionType::string, "0D00",
     "the monitor holding the output frequency (speed_rpm); polled even when not in monitors"},
    {"parameters", OptionType::string_list, "",
     "drive parameters GG-nn to expose as holding points param_GG_nn (read 03, written 06)"},
    // Document, "communication material structure": >= 10 ms of silence around every frame.
    {"frame_gap_ms", OptionType::integer, "10", "line silence before every frame, ms", 10, 1000},
    {"timeout_ms", OptionType::integer, "100", "reply timeout per attempt, ms", 20, 5000},
    {"attempts", OptionType::integer, "3", "sends of a frame before giving up on it", 1, 10},
    {"comm_timeout_ms", OptionType::integer, "3000", "no good reply for this long: comm_lost", 500,
     600000},
    // Not in the document: README.md, "Choices", 2 (0x2002 = 8194, bit 1 = 2).
    {"reset_register", OptionType::integer, "8194",
     "register written for reset_fault (default 0x2002)", 0, 65535},
    {"reset_value", OptionType::integer, "2", "value written for reset_fault (bit 1)", 0, 65535},
    {"sim_reply_form", OptionType::string, "document",
     "simulator only: 03 replies in the document's form or the standard one", 0, 0,
     "document|standard"},
}};

// A monitor to poll and expose.
struct MonitorSel {
  std::uint16_t reg = 0;  // 0x0D00..0x0D28
  std::string unit;       // "V", "Hz", "A" or "" (from a ":unit" suffix)
};

struct Settings {
  int poles = 4;
  std::vector<MonitorSel> monitors;       // polled and exposed, speed monitor included
  std::size_t speed_monitor = 0;          // index into monitors
  std::vector<std::uint16_t> parameters;  // 0xGGnn
  Millis frame_gap{10};
  Millis timeout{100};
  std::uint8_t attempts = 3;
  Millis comm_timeout{3000};
  std::uint16_t reset_register = 0x2002;
  std::uint16_t reset_value = 0x0002;
  ReadForm sim_reply_form = ReadForm::document;
};

// "0D00", "0d05:Hz": a monitor register and its unit.
std::optional<MonitorSel> parse_monitor(std::string_view text);
// "04-01" -> 0x0401 (the digits are the address's hex digits, document "GGnnH").
std::optional<std::uint16_t> parse_parameter(std::string_view text);

// The options as the driver and simulator use them: nullopt with `error` naming the option when
// they do not make a device (an odd pole count, a monitor or parameter that is not one, or one
// listed twice).
std::optional<Settings> parse_settings(const Options& options, std::string& error);

// The device's bus address, 0 (broadcast) or 1..31 (document, "Address"): nullopt with `error`
// otherwise.
std::optional<std::uint8_t> device_address(std::uint32_t address, std::string& error);

}  // namespace drivegate::ed3100
