// Store and forward for the Sparkplug edge node (docs/mqtt.md): the changes the edge node keeps
// while it has no session (EdgeNode's Sink::store) go to a Spool on disk, each as a record of the
// device's name and the historical DDATA payload; once a session is online they are replayed,
// oldest first, through EdgeNode::replay() at a bounded pace, beside the live data.
//
// Nothing leaves it before the broker has it: a change leaves the store only once the broker has
// provably received the message that carried it (MosquittoClient's delivery confirmation,
// delivered()), and so does a live DDATA or DBIRTH, held here as history meanwhile (sent()). When
// the session ends first (lost()), the records replayed and not confirmed are read again, and the
// live messages not confirmed are kept as historical DDATA after them: what went out on a link
// that turned out dead is replayed in the next session. The host may so see a change twice (live,
// then as history): only those published after the last confirmation (kConfirmDelay plus the
// time an answer takes, on a live link). A record counts as replayed once it is confirmed.
//
// The records replayed and not yet confirmed are at most a window, which starts at one record
// in each session and doubles with each confirmation (up to a second's worth, per_second): a
// link that is cut after every few kilobytes still carries a few records each time, and the
// replay makes progress instead of sending the same records into every cut.
#pragma once

#include <spdlog/logger.h>

#include <cstdint>
#include <deque>
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
  // At most `max` records (one batch when 0), if the edge node is online: how many were taken
  // (sent or dropped; 0: none could go now).
  unsigned replay(sparkplug::EdgeNode& edge, sparkplug::Sink& sink, const sparkplug::Now& now,
                  unsigned max = 0);
  // The MQTT client took message `number` (MosquittoClient::published()) on `topic`: a record
  // replay() is publishing, or a live message, held as history (sparkplug::as_history) until
  // delivered() or lost().
  void sent(std::uint64_t number, std::string_view topic, const sparkplug::Payload& payload);
  // The broker has received every message up to `number`: they leave the store.
  void delivered(std::uint64_t number);
  // The session ended: what it did not confirm is kept for the next (above).
  void lost(std::uint64_t now_ms);
  // Data and cursor to disk (once a second, and at stop).
  void sync();

  [[nodiscard]] StoreStats stats(const sparkplug::EdgeNode& edge) const;
  // Records not sent yet in this session.
  [[nodiscard]] bool waiting() const { return spool_.stats().records > spool_.taken_unreleased(); }
  [[nodiscard]] unsigned batch() const { return batch_; }
  // As many records as the window allows are out: nothing more until a confirmation (ask for one).
  [[nodiscard]] bool window_full() const { return records_out_ >= window_; }

  static constexpr std::chrono::milliseconds kReplayPeriod{100};

 private:
  // A message taken by the client and not yet confirmed: a record of the spool (whose end is
  // `replayed`), or a live one's history.
  struct Unconfirmed {
    std::uint64_t number = 0;
    std::optional<SpoolPosition> replayed;
    std::string device;
    sparkplug::Payload history;
  };
  // Taken records that are not waiting for a confirmation (dropped, unreadable) leave with the
  // confirmed ones before them, or at once when none is out.
  void release_settled();

  Spool spool_;
  unsigned batch_;
  unsigned max_window_;  // a second's worth
  unsigned window_ = 1;
  std::shared_ptr<spdlog::logger> log_;
  std::deque<Unconfirmed> unconfirmed_;         // in the order the client took them
  std::size_t records_out_ = 0;                 // of unconfirmed_, records of the spool
  std::optional<std::uint64_t> replay_number_;  // sent() during replay(): the record's number
  bool replaying_ = false;
  std::uint64_t replayed_ = 0;
  std::uint64_t unreadable_ = 0;
  bool failing_ = false;       // a disk error was logged; the next success says it is over
  bool read_failing_ = false;  // the same, reading for a replay (said once)
  bool sync_failing_ = false;  // the same, syncing (said once)
};

}  // namespace drivegate::mqtt
