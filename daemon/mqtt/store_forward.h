// Store and forward for the Sparkplug edge node (issue 29, docs/mqtt.md): the changes the edge
// node keeps while it has no session (EdgeNode's Sink::store) go to a Spool on disk, each as a
// record of the device's name and the historical DDATA payload; once a session is online they are
// replayed, oldest first, through EdgeNode::replay() at a bounded pace, beside the live data.
#pragma once

#include <spdlog/logger.h>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "mqtt/edge_node.h"
#include "mqtt/northbound_status.h"
#include "mqtt/spool.h"

namespace drivegate::mqtt {

// A record: u16 length of the device name (little-endian), the name, the payload's protobuf.
std::string encode_record(std::string_view device, const sparkplug::Payload& payload);
struct StoredChange {
  std::string device;
  sparkplug::Payload payload;
};
std::optional<StoredChange> decode_record(std::string_view bytes);

class StoreForward {
 public:
  // `per_second`: the replay's pace; a batch of per_second / 10 every 100 ms (kReplayPeriod).
  StoreForward(std::filesystem::path dir, SpoolLimits limits, unsigned per_second,
               std::shared_ptr<spdlog::logger> log);

  // Opens the spool (what a run before left is kept); logs what it found and any refusal.
  bool open();
  void keep(std::string_view device, const sparkplug::Payload& historical, std::uint64_t now_ms);
  // One batch, if the edge node is online: whether records still wait.
  bool replay(sparkplug::EdgeNode& edge, sparkplug::Sink& sink, std::uint64_t now_ms);
  // Data and cursor to disk (once a second, and at stop).
  void sync();

  [[nodiscard]] StoreStats stats(const sparkplug::EdgeNode& edge) const;
  [[nodiscard]] bool waiting() const { return !spool_.empty(); }

  static constexpr std::chrono::milliseconds kReplayPeriod{100};

 private:
  Spool spool_;
  unsigned batch_;
  std::shared_ptr<spdlog::logger> log_;
  std::uint64_t replayed_ = 0;
  std::uint64_t unreadable_ = 0;
  bool failing_ = false;       // a disk error was logged; the next success says it is over
  bool read_failing_ = false;  // the same, reading for a replay (said once)
  bool sync_failing_ = false;  // the same, syncing (said once)
};

}  // namespace drivegate::mqtt
