// What the MQTT northbound shows of itself (/metrics, /api/v1/status): plain data, so that the
// documents' renderers (daemon/format) read it without depending on the northbound.
#pragma once

#include <cstdint>
#include <string>

namespace drivegate::mqtt {

struct NorthboundStatus {
  std::string broker;
  std::string session = "offline";  // offline, waiting_for_host or online (edge_node.h)
  bool connected = false;
  std::uint8_t bd_seq = 0;
  std::uint64_t connects = 0;  // sessions begun (CONNACK)
  std::uint64_t losses = 0;    // attempts failed or sessions lost
  std::uint64_t messages = 0;  // Sparkplug messages published
  std::uint64_t births = 0;    // DBIRTHs among them
  std::uint64_t commands = 0;  // DCMD writes carried out (any outcome)
  std::uint64_t commands_retained = 0;   // NCMD / DCMD ignored: retained by the broker
  std::uint64_t rebirths_coalesced = 0;  // rebirth requests answered by a later rebirth
  std::string last_error;      // why the last attempt or session failed; empty once connected
};

}  // namespace drivegate::mqtt
