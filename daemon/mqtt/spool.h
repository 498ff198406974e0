// A bounded, disk-backed queue of records, oldest first: what the Sparkplug edge node keeps while
// it has no session, to send later (store and forward, docs/mqtt.md). The records are opaque
// bytes with the Unix time they were stored at; what they hold is the caller's.
//
// On disk, under one directory: segment files "<16 hex digits>.seg" in the order of their names,
// each a run of records
//
//   u32 length   of what follows the header (little-endian)
//   u32 crc32    IEEE 802.3, of the stored time and the bytes
//   u64 time     Unix ms when the record was stored
//   length bytes
//
// and "cursor", the first record not yet released ("<segment> <offset>\n"). Appends go to the
// last segment (a new one once it holds segment_bytes); segments wholly released are deleted;
// beyond max_bytes the oldest segment goes, its records counted as dropped.
//
// Reading runs ahead of the cursor: take() passes a record on, which stays kept (counted in
// records, and on disk) until release() says the reader is done with everything up to a
// position(), or rewind() reads again from the cursor. The edge node takes what it publishes and
// releases it once the broker confirmed it (store_forward.h); pop() is take() and release at
// once. Nothing is synced by append or release: sync() (the owner calls it once a second) syncs
// the segment written and replaces the cursor file, so a power cut loses at most what came after
// the last sync() and replays at most what was released after it. Opening scans every segment: a
// record damaged or cut short costs that record, not its segment: the scan goes on at the next
// record that checks out (a header whose length fits and whose CRC holds), the bytes in between
// counted and skipped; a segment is never written to after the run that made it. A cursor that is
// not on a record of a segment that exists is ignored and everything kept is replayed.
//
// Nothing in the directory is trusted to be what its name says (base/state_file.h): every file
// is opened without following a link or blocking, through the directory's own descriptor, and
// used only when it is a regular file; a segment is made anew (O_EXCL) and the cursor replaced
// through a fresh temporary. What has a segment's or the cursor's name and is not a regular file
// (a FIFO, a link, a directory) is set aside ("<name>.bad") and said through the Note, and the
// store goes on. A directory deleted or replaced while the spool runs (found by sync(), or when a
// file cannot be made) is made again, and what its open segments still held that was not taken
// is carried over into it (what was taken and not released too: it is read again, and the
// positions taken before are released no more); the records only the other files held are
// counted lost. A segment that cannot be read on is given up only once what was taken before it
// is released.
//
// Errors are std::error_code; a spool whose directory cannot be written keeps what it had taken
// in and refuses the rest (counted), and the owner goes on without it.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

namespace drivegate::mqtt {

struct SpoolLimits {
  std::uint64_t max_bytes = 64ULL * 1024 * 1024;  // on disk, headers included
  std::chrono::milliseconds max_age{std::chrono::hours(24)};
  std::uint64_t segment_bytes = 0;  // 0: max_bytes / 16, at least 4 KiB
};

struct SpoolStats {
  std::uint64_t bytes = 0;    // on disk, not yet released or dropped
  std::uint64_t records = 0;  // waiting: not taken, or taken and not released
  std::uint64_t appended = 0;
  std::uint64_t taken = 0;
  std::uint64_t dropped_size = 0;     // records lost to max_bytes (oldest first)
  std::uint64_t dropped_age = 0;      // records older than max_age when their turn came
  std::uint64_t dropped_corrupt = 0;  // bytes found cut short or damaged, skipped
  std::uint64_t dropped_lost = 0;  // records lost with their file: deleted, moved or damaged later
  std::uint64_t refused = 0;       // appends the disk refused
  std::optional<std::uint64_t> oldest_ms;  // the stored time of the oldest waiting record
};

// Where reading has got to: after the last record taken.
struct SpoolPosition {
  std::uint64_t segment = 0;
  std::uint64_t offset = 0;   // in the segment's file
  std::uint64_t records = 0;  // before it in the segment
  std::uint64_t files = 0;    // the spool's files it is in: a directory made again, new ones
};

struct SpoolRecord {
  std::uint64_t stored_ms = 0;
  std::string bytes;
};

class Spool {
 public:
  // What the spool did to go on, for the owner's log: a file set aside, damage skipped, the
  // directory made again. Each is said once, when it happens.
  using Note = std::function<void(const std::string&)>;

  Spool(std::filesystem::path dir, SpoolLimits limits, Note note = {});
  ~Spool();
  Spool(const Spool&) = delete;
  Spool& operator=(const Spool&) = delete;

  // Creates the directory if need be (setting aside what has its name and is not one) and reads
  // what an earlier run left (above).
  std::error_code open();
  std::error_code append(std::uint64_t stored_ms, std::string_view bytes);
  // The oldest record not yet taken; those older than max_age at `now_ms` are dropped on the way
  // (counted once, taken). nullopt: nothing waits (or it cannot be read: `error` says why).
  std::optional<SpoolRecord> front(std::uint64_t now_ms, std::error_code& error);
  // Takes front()'s record: front() goes on to the next; it stays kept until released.
  void take();
  // After the last record taken.
  [[nodiscard]] SpoolPosition position() const;
  // Everything taken before `p` (a position() of this spool) is done with: gone from the spool,
  // and the cursor moves there. A position at or before the cursor, or of files made again
  // since, changes nothing.
  void release(const SpoolPosition& p);
  // Reading goes back to the cursor: what was taken and not released is read again.
  void rewind();
  // take() and release() of front()'s record: it is gone.
  void pop();
  std::error_code sync();

  [[nodiscard]] bool empty() const { return stats_.records == 0; }
  // Records taken and not yet released.
  [[nodiscard]] std::uint64_t taken_unreleased() const;
  [[nodiscard]] const SpoolStats& stats() const { return stats_; }
  [[nodiscard]] const std::filesystem::path& dir() const { return dir_; }

  static constexpr std::size_t kHeader = 16;
  static constexpr std::uint32_t kMaxRecord = 16 * 1024 * 1024;  // a length beyond: damage

 private:
  struct Segment {
    std::uint64_t id = 0;
    std::uint64_t bytes = 0;    // its records' end (damage after the last one is left out)
    std::uint64_t records = 0;  // in it, taken ones included
    // Runs of damaged bytes [from, to) between records, skipped.
    std::vector<std::pair<std::uint64_t, std::uint64_t>> damaged;
    // `at`, or where the damaged run that starts there ends.
    [[nodiscard]] std::uint64_t skip(std::uint64_t at) const;
  };
  [[nodiscard]] static std::string name_of(std::uint64_t id);
  std::error_code open_dir();
  [[nodiscard]] bool dir_moved() const;
  std::error_code recover();
  void scan(Segment& s, int fd, std::uint64_t size);
  void read_cursor();
  std::error_code start_segment();
  void drop_front_segment();
  void lose_front_segment(const std::string& why);
  void close_reader();
  void trim_to_size();
  // The stored time of the record at the cursor (the oldest waiting), into stats_.oldest_ms.
  void find_oldest();
  void set_aside(const std::string& name, const std::string& what);
  void note(const std::string& text) const;

  std::filesystem::path dir_;
  SpoolLimits limits_;
  Note note_;
  int dir_fd_ = -1;  // the directory open_dir() opened: every file is reached through it
  std::deque<Segment> segments_;
  std::uint64_t next_id_ = 1;         // the next segment's: ids are never used twice in a run
  std::uint64_t cursor_offset_ = 0;   // in the front segment
  std::uint64_t cursor_records_ = 0;  // released there
  SpoolPosition read_;                // where front() reads: at or after the cursor
  SpoolPosition read_high_;           // the furthest read_ has been (dropped_age counts once)
  std::uint64_t files_ = 0;           // recover() made the directory again this many times
  std::uint64_t front_bytes_ = 0;     // front()'s record's size on disk, 0: none read
  int writer_ = -1;                   // the back segment, appended to (and read, to carry over)
  int reader_ = -1;                   // the front segment
  std::uint64_t reader_id_ = 0;
  bool dirty_ = false;         // appended since the last sync()
  bool cursor_moved_ = false;  // taken since the last sync()
  SpoolStats stats_;
};

// IEEE 802.3 CRC-32 (the zlib / PNG one), continued from `crc` (0 to start).
std::uint32_t crc32_ieee(std::string_view bytes, std::uint32_t crc = 0);

}  // namespace drivegate::mqtt
