#include "schema.h"

#include "config.h"
#include "driver.h"
#include "simulator.h"

namespace drivegate::ed3100 {

const std::array<OptionSpec, 11> kOptionSpecs = {{
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
    // Not in the document: see README.md, "Fault reset".
    {"reset_register", OptionType::integer, "8194",
     "register written for reset_fault (default 0x2002)", 0, 65535},
    {"reset_value", OptionType::integer, "2", "value written for reset_fault (bit 1)", 0, 65535},
    {"sim_reply_form", OptionType::string, "document",
     "simulator only: 03 replies in the document's form or the standard one", 0, 0,
     "document|standard"},
}};

std::unique_ptr<Driver> create_driver(const DeviceEnv& env, std::string& error) {
  auto config = make_config(env.address, env.options, error);
  if (!config) return nullptr;
  return std::make_unique<Ed3100Driver>(std::move(*config), env.poll_interval);
}

std::unique_ptr<Simulator> create_simulator(const SimEnv& env, std::string& error) {
  if (env.address > 31) {  // document, "Address": 0 ~ 31
    error = "address: the ED3100 takes 0 (broadcast) or 1..31";
    return nullptr;
  }
  const ReadForm form =
      env.options.string("sim_reply_form") == "standard" ? ReadForm::standard : ReadForm::document;
  return std::make_unique<Ed3100Simulator>(static_cast<std::uint8_t>(env.address), form);
}

}  // namespace drivegate::ed3100
