// What the MQTT northbound shows of itself (/metrics, /api/v1/status): plain data, so that the
// documents' renderers (daemon/format) read it without depending on the northbound.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

namespace drivegate::mqtt {

// Store and forward (store_forward.h, spool.h).
struct StoreStats {
  bool enabled = false;
  std::uint64_t records = 0;               // kept, waiting to be sent
  std::uint64_t bytes = 0;                 // on disk
  std::optional<std::uint64_t> oldest_ms;  // when the oldest waiting was kept (Unix ms)
  std::uint64_t kept = 0;
  std::uint64_t replayed = 0;         // published as historical DDATA
  std::uint64_t dropped_size = 0;     // beyond store_max_mb, oldest first
  std::uint64_t dropped_age = 0;      // older than store_max_age_h when their turn came
  std::uint64_t dropped_corrupt = 0;  // bytes cut short or damaged, skipped
  std::uint64_t dropped_lost = 0;     // lost with their file: deleted, or damaged later
  std::uint64_t refused = 0;          // the disk refused them
  std::uint64_t replay_dropped = 0;   // unreadable, or for a device not born now
};

struct NorthboundStatus {
  std::string broker;                 // the broker in use (its URL), one of [mqtt] brokers
  std::size_t broker_index = 0;       // its place in the list, from 0
  std::size_t brokers = 1;            // how many there are
  std::uint64_t broker_switches = 0;  // moves to the next broker after a failure
  std::string session = "offline";    // offline, waiting_for_host or online (edge_node.h)
  bool connected = false;
  std::uint8_t bd_seq = 0;
  std::uint64_t connects = 0;            // sessions begun (CONNACK)
  std::uint64_t losses = 0;              // attempts failed or sessions lost
  std::uint64_t sessions_lost = 0;       // of them, sessions that were up (one an outage)
  std::uint64_t messages = 0;            // Sparkplug messages published
  std::uint64_t births = 0;              // DBIRTHs among them
  std::uint64_t commands = 0;            // DCMD writes carried out (any outcome)
  std::uint64_t commands_retained = 0;   // NCMD / DCMD ignored: retained by the broker
  std::uint64_t rebirths_coalesced = 0;  // rebirth requests answered by a later rebirth
  std::string last_error;  // why the last attempt or session failed; empty once connected
  StoreStats store;        // store and forward (enabled false: none)
};

}  // namespace drivegate::mqtt
