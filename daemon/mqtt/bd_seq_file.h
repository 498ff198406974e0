// The bdSeq of an edge node's latest session, kept across restarts (Sparkplug B 3.0,
// 6.4.19 and 7.2: a host pairs an NDEATH with the NBIRTH of the same bdSeq, so a node that began
// again at 0 after a crash could have its new session taken for the old one's death).
//
// One file per edge node under the state directory, "sparkplug-<group>-<edge node>.bdseq", that
// holds the number in decimal and a newline. It is written before each MQTT CONNECT whose will
// carries the new bdSeq (base/state_file.h: replaced whole or not at all), so a process killed at
// any point leaves the bdSeq of the last will the broker may hold, and the next start goes one on.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace drivegate::mqtt {

class BdSeqFile {
 public:
  // `state_dir` empty: nothing is kept (load() says nothing, save() does nothing).
  BdSeqFile(const std::filesystem::path& state_dir, std::string_view group,
            std::string_view edge_node);

  // The bdSeq saved last; nothing when there is no file yet (`error` empty) or when it cannot be
  // read or holds no number 0..255 (`error` says which and why; the caller starts at 0). What
  // has the file's name and is no regular file (a FIFO, a link, a directory) is never opened:
  // it is set aside (base/state_file.h) and `error` says so.
  std::optional<std::uint8_t> load(std::string& error) const;
  // Writes it (base/state_file.h: a fresh temporary, synced, renamed); a state directory deleted
  // while the daemon runs is made again.
  std::error_code save(std::uint8_t bd_seq) const;

  [[nodiscard]] bool enabled() const { return !path_.empty(); }
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// What an edge node keeps in the state directory is named for it:
// "<dir>/sparkplug-<group>-<edge node><extension>" (".bdseq" here, ".store" for store_forward.h).
std::filesystem::path edge_node_state_path(const std::filesystem::path& dir, std::string_view group,
                                           std::string_view edge_node, std::string_view extension);
// The same kind of state as `own` (an edge_node_state_path: same directory, same extension) of
// the other edge nodes: what a configuration whose group_id or edge_node_id changed left behind,
// which nothing reads now.
std::vector<std::filesystem::path> other_edge_node_state(const std::filesystem::path& own);

// "17\n" -> 17; anything but a number 0..255 and at most one trailing newline: nothing.
std::optional<std::uint8_t> parse_bd_seq(std::string_view text);

}  // namespace drivegate::mqtt
