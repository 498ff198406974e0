#include "mqtt/spool.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <vector>

#include "base/read_file.h"
#include "base/state_file.h"

namespace drivegate::mqtt {

namespace {

namespace fs = std::filesystem;

std::error_code last_error() {
  return {errno, std::generic_category()};
}

constexpr std::array<std::uint32_t, 256> kCrcTable = [] {
  std::array<std::uint32_t, 256> t{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1U) != 0 ? 0xEDB88320U ^ (c >> 1) : c >> 1;
    t[i] = c;
  }
  return t;
}();

void put_le(std::uint8_t* p, std::uint64_t v, int n) {
  for (int i = 0; i < n; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
std::uint64_t get_le(const std::uint8_t* p, int n) {
  std::uint64_t v = 0;
  for (int i = n - 1; i >= 0; --i) v = v << 8 | p[i];
  return v;
}

// The CRC of a record: its stored time (8 bytes, little-endian) and its bytes.
std::uint32_t record_crc(const std::uint8_t* time, std::string_view bytes) {
  const std::uint32_t c = crc32_ieee(std::string_view(reinterpret_cast<const char*>(time), 8), 0);
  return crc32_ieee(bytes, c);
}

bool read_exact(int fd, void* buf, std::size_t n, std::uint64_t at) {
  auto* p = static_cast<std::uint8_t*>(buf);
  while (n > 0) {
    const ssize_t r = ::pread(fd, p, n, static_cast<off_t>(at));
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) return false;
    p += r;
    n -= static_cast<std::size_t>(r);
    at += static_cast<std::uint64_t>(r);
  }
  return true;
}

std::optional<std::uint64_t> segment_id(const std::string& name) {
  if (name.size() != 20 || !name.ends_with(".seg")) return std::nullopt;
  std::uint64_t id = 0;
  const auto [end, ec] = std::from_chars(name.data(), name.data() + 16, id, 16);
  if (ec != std::errc() || end != name.data() + 16) return std::nullopt;
  return id;
}

// A file read forward through a buffer: a few large reads for a segment's scan, not two per
// record.
class Window {
 public:
  Window(int fd, std::uint64_t size) : fd_(fd), size_(size) {}
  // The `n` bytes at `at` (valid until the next call), or nullptr when the file does not hold
  // them all.
  const std::uint8_t* get(std::uint64_t at, std::uint64_t n) {
    if (at > size_ || n > size_ - at) return nullptr;
    if (at < start_ || at + n > start_ + buf_.size()) {
      const std::uint64_t want = std::max(n, std::min(kChunk, size_ - at));
      buf_.resize(want);
      if (!read_exact(fd_, buf_.data(), want, at)) {
        buf_.clear();
        return nullptr;
      }
      start_ = at;
    }
    return reinterpret_cast<const std::uint8_t*>(buf_.data()) + (at - start_);
  }

 private:
  static constexpr std::uint64_t kChunk = 256 * 1024;
  int fd_;
  std::uint64_t size_;
  std::uint64_t start_ = 0;
  std::string buf_;
};

// A stored time past this (the year 10889) is no Unix time in ms: a header that has one is not
// taken for a record's when looking for the next record after damage.
constexpr std::uint64_t kMaxStoredMs = 1ULL << 48;

// The size on disk of the record at `at` when it is whole and its CRC holds, else 0.
// `resyncing`: looking for a record after damage, where the header must look like one first.
std::uint64_t record_size(Window& w, std::uint64_t at, bool resyncing) {
  const std::uint8_t* h = w.get(at, Spool::kHeader);
  if (h == nullptr) return 0;
  const std::uint64_t length = get_le(h, 4);
  if (length > Spool::kMaxRecord) return 0;
  if (resyncing && get_le(h + 8, 8) >= kMaxStoredMs) return 0;
  const auto crc = static_cast<std::uint32_t>(get_le(h + 4, 4));
  const std::uint8_t* r = w.get(at, Spool::kHeader + length);
  if (r == nullptr) return 0;
  // The stored time and the bytes are contiguous: the CRC covers both (record_crc).
  const std::string_view covered(reinterpret_cast<const char*>(r + 8), 8 + length);
  return crc32_ieee(covered) == crc ? Spool::kHeader + length : 0;
}

// Where the first record that checks out after damage at `at` starts, or nothing: the rest of
// the file is damaged or cut short. Every offset is tried, so a damaged length field costs no
// more than the record it belongs to.
std::optional<std::uint64_t> next_record(Window& w, std::uint64_t at, std::uint64_t size) {
  for (std::uint64_t o = at + 1; o + Spool::kHeader <= size; ++o) {
    if (record_size(w, o, true) != 0) return o;
  }
  return std::nullopt;
}

constexpr int kNewFile = O_RDWR | O_CREAT | O_EXCL | O_APPEND | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC;
constexpr const char* kCursor = "cursor";

// What an error of base/read_file.h says after the file's name ("x.seg: a FIFO, ...").
std::string after_name(const std::string& error) {
  const auto colon = error.find(": ");
  return colon == std::string::npos ? error : error.substr(colon + 2);
}

bool before(const SpoolPosition& a, const SpoolPosition& b) {
  return a.segment < b.segment || (a.segment == b.segment && a.offset < b.offset);
}

std::string plural(std::uint64_t n, const char* one, const char* many) {
  return std::to_string(n) + " " + (n == 1 ? one : many);
}

}  // namespace

std::uint32_t crc32_ieee(std::string_view bytes, std::uint32_t crc) {
  crc = ~crc;
  for (const char ch : bytes) {
    crc = kCrcTable[(crc ^ static_cast<std::uint8_t>(ch)) & 0xFFU] ^ (crc >> 8);
  }
  return ~crc;
}

Spool::Spool(std::filesystem::path dir, SpoolLimits limits, Note note)
    : dir_(std::move(dir)), limits_(limits), note_(std::move(note)) {
  if (limits_.segment_bytes == 0) {
    limits_.segment_bytes = std::max<std::uint64_t>(limits_.max_bytes / 16, 4096);
  }
}

Spool::~Spool() {
  close_reader();
  if (writer_ >= 0) ::close(writer_);
  if (dir_fd_ >= 0) ::close(dir_fd_);
}

std::uint64_t Spool::Segment::skip(std::uint64_t at) const {
  for (const auto& [from, to] : damaged) {
    if (from == at) return to;
  }
  return at;
}

std::string Spool::name_of(std::uint64_t id) {
  std::array<char, 21> name{};
  std::snprintf(name.data(), name.size(), "%016llx.seg", static_cast<unsigned long long>(id));
  return name.data();
}

void Spool::note(const std::string& text) const {
  if (note_) note_(text);
}

void Spool::set_aside(const std::string& name, const std::string& what) {
  std::string error;
  const auto to = drivegate::set_aside(dir_fd_, name, error);
  note(to ? name + ": " + what + "; set aside as " + *to : error + " (" + what + ")");
}

// Opens the directory (made if need be) as dir_fd_. What has its name and is no directory (a
// file, a FIFO, a link to a directory elsewhere) is set aside first.
std::error_code Spool::open_dir() {
  struct stat st {};
  if (::lstat(dir_.c_str(), &st) == 0 && !S_ISDIR(st.st_mode)) {
    std::string error;
    const auto to = drivegate::set_aside(AT_FDCWD, dir_.string(), error);
    note(to ? std::string(file_kind(st.st_mode)) + " had the store's name; set aside as " + *to
            : error);
  }
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec) return ec;
  const int fd = ::open(dir_.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) return last_error();
  if (dir_fd_ >= 0) ::close(dir_fd_);
  dir_fd_ = fd;
  return {};
}

// Whether the directory open as dir_fd_ was deleted, or is no longer the one at dir_'s path (moved,
// or deleted and made again by someone else).
bool Spool::dir_moved() const {
  struct stat held {};
  struct stat named {};
  if (::fstat(dir_fd_, &held) != 0 || held.st_nlink == 0) return true;
  return ::lstat(dir_.c_str(), &named) != 0 || named.st_dev != held.st_dev ||
         named.st_ino != held.st_ino;
}

std::error_code Spool::open() {
  if (auto ec = open_dir()) return ec;
  std::vector<std::uint64_t> ids;
  std::vector<std::string> strange;  // segment names that are no regular files
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir_, ec)) {
    const std::string name = e.path().filename().string();
    const auto id = segment_id(name);
    if (!id || name_of(*id) != name) continue;  // not a name this writes ("...A.seg")
    std::error_code type_ec;
    if (e.symlink_status(type_ec).type() == fs::file_type::regular) {
      ids.push_back(*id);
    } else {
      strange.push_back(name);
    }
  }
  if (ec) return ec;
  for (const std::string& name : strange) {
    struct stat st {};
    ::fstatat(dir_fd_, name.c_str(), &st, AT_SYMLINK_NOFOLLOW);
    set_aside(name, std::string(file_kind(st.st_mode)) + ", not a segment");
  }
  std::sort(ids.begin(), ids.end());
  for (const std::uint64_t id : ids) {
    next_id_ = std::max(next_id_, id + 1);
    std::string why;
    const int fd = open_regular_file(dir_fd_, name_of(id), O_RDONLY, Links::refuse, why);
    if (fd < 0) {  // changed since it was listed
      if (errno != ENOENT) set_aside(name_of(id), after_name(why));
      continue;
    }
    struct stat st {};
    ::fstat(fd, &st);
    Segment s{id, 0, 0, {}};
    scan(s, fd, static_cast<std::uint64_t>(st.st_size));
    ::close(fd);
    segments_.push_back(std::move(s));
  }
  read_cursor();
  for (const Segment& s : segments_) {
    stats_.bytes += s.bytes;
    stats_.records += s.records;
  }
  stats_.bytes -= cursor_offset_;
  stats_.records -= cursor_records_;
  rewind();
  read_high_ = read_;
  find_oldest();
  return {};
}

// Counts a segment's records. A record damaged or cut short is skipped up to the next one that
// checks out (its run of bytes kept in `damaged`); after the last, it ends the segment. The file
// is only read: it may be a hard link of someone's (a backup's), never to be written through.
void Spool::scan(Segment& s, int fd, std::uint64_t size) {
  Window w(fd, size);
  std::uint64_t at = 0;
  std::uint64_t damaged = 0;
  while (at < size) {
    if (const std::uint64_t n = record_size(w, at, false)) {
      at += n;
      ++s.records;
      continue;
    }
    const auto next = next_record(w, at, size);
    if (!next) break;
    s.damaged.emplace_back(at, *next);
    damaged += *next - at;
    at = *next;
  }
  s.bytes = at;
  stats_.dropped_corrupt += damaged + (size - at);
  const std::string name = name_of(s.id);
  if (damaged != 0) {
    note(name + ": " + plural(damaged, "damaged byte", "damaged bytes") + " in " +
         plural(s.damaged.size(), "place", "places") + " left out; the " +
         plural(s.records, "record", "records") + " around them kept");
  }
  if (at < size) {
    note(name + ": its last " + plural(size - at, "byte", "bytes") +
         " are no whole record (cut short by a power cut while writing, or damaged): left out");
  }
}

// "<segment> <offset>\n", believed only when it names a record boundary of a kept segment
// (checked by walking that segment's headers); else everything kept is replayed.
void Spool::read_cursor() {
  std::string error;
  const int fd = open_regular_file(dir_fd_, kCursor, O_RDONLY, Links::refuse, error);
  if (fd < 0) {
    if (errno != ENOENT) set_aside(kCursor, after_name(error));
    return;
  }
  std::array<char, 256> buf{};
  const ssize_t got = ::pread(fd, buf.data(), buf.size(), 0);
  ::close(fd);
  if (got <= 0 || segments_.empty()) return;
  std::uint64_t id = 0;
  std::uint64_t offset = 0;
  const char* p = buf.data();
  const char* end = p + got;
  auto r = std::from_chars(p, end, id, 16);
  if (r.ec != std::errc() || r.ptr == end || *r.ptr != ' ') return;
  r = std::from_chars(r.ptr + 1, end, offset);
  if (r.ec != std::errc()) return;
  const auto seg = std::find_if(segments_.begin(), segments_.end(),
                                [&](const Segment& s) { return s.id == id; });
  if (seg == segments_.end() || offset > seg->bytes) return;
  std::string why;
  const int sfd = open_regular_file(dir_fd_, name_of(id), O_RDONLY, Links::refuse, why);
  if (sfd < 0) return;
  Window w(sfd, seg->bytes);
  std::uint64_t at = 0;
  std::uint64_t records = 0;
  while (at < offset) {
    at = seg->skip(at);  // a cursor at the start or the end of a damaged run is on a boundary
    if (at >= offset) break;
    const std::uint8_t* h = w.get(at, kHeader);
    if (h == nullptr) break;
    at += kHeader + get_le(h, 4);
    ++records;
  }
  ::close(sfd);
  if (at != offset) return;
  // The segments before the cursor's were taken whole: gone.
  while (segments_.front().id != id) {
    ::unlinkat(dir_fd_, name_of(segments_.front().id).c_str(), 0);
    segments_.pop_front();
  }
  cursor_offset_ = offset;
  cursor_records_ = records;
}

// The segment written so far stays open until the next is made: should the directory be gone,
// recover() carries over what it holds.
std::error_code Spool::start_segment() {
  for (int attempt = 0;; ++attempt) {
    const std::uint64_t id = next_id_;
    const std::string name = name_of(id);
    const int fd = ::openat(dir_fd_, name.c_str(), kNewFile, 0600);
    if (fd >= 0) {
      if (writer_ >= 0) ::close(writer_);
      writer_ = fd;
      ++next_id_;
      segments_.push_back({id, 0, 0, {}});
      return {};
    }
    if (errno != EEXIST || attempt > 0) return last_error();
    // Made since open() by someone else (a FIFO, a link, a file): not this run's. Set aside; if it
    // cannot be, the next name is taken.
    struct stat st {};
    ::fstatat(dir_fd_, name.c_str(), &st, AT_SYMLINK_NOFOLLOW);
    set_aside(name, std::string(file_kind(st.st_mode)) + " made while the store ran");
    if (::fstatat(dir_fd_, name.c_str(), &st, AT_SYMLINK_NOFOLLOW) == 0) ++next_id_;
  }
}

// The directory was deleted or moved while the spool ran (the state directory removed by hand):
// it is made again, and what the segments this has open (the one written, the one read) still
// hold that was not taken is carried over into files of the same names there, so that what was
// kept after the deletion is not written into a file nobody can open. The records of the other
// segments went with their files: counted lost.
std::error_code Spool::recover() {
  if (auto ec = open_dir()) return ec;
  std::deque<Segment> kept;
  std::uint64_t carried = 0;
  std::uint64_t lost = 0;
  int writer = -1;
  for (std::size_t i = 0; i < segments_.size(); ++i) {
    const Segment& s = segments_[i];
    const bool front = i == 0;
    const bool back = i + 1 == segments_.size();
    const std::uint64_t waiting = s.records - (front ? cursor_records_ : 0);
    int from = -1;
    if (back && writer_ >= 0) {
      from = writer_;
    } else if (reader_ >= 0 && reader_id_ == s.id) {
      from = reader_;
    }
    if (waiting == 0 && !back) continue;
    const int to = from >= 0 ? ::openat(dir_fd_, name_of(s.id).c_str(), kNewFile, 0600) : -1;
    if (to < 0) {
      lost += waiting;
      continue;
    }
    Segment copy{s.id, 0, 0, {}};
    Window w(from, s.bytes);
    for (std::uint64_t at = s.skip(front ? cursor_offset_ : 0); at < s.bytes; at = s.skip(at)) {
      const std::uint64_t n = record_size(w, at, false);
      const std::uint8_t* r = n != 0 ? w.get(at, n) : nullptr;
      if (r == nullptr || write_all(to, {reinterpret_cast<const char*>(r), n})) break;
      at += n;
      copy.bytes += n;
      ++copy.records;
    }
    lost += waiting - copy.records;
    carried += copy.records;
    if (back) {
      writer = to;
    } else {
      ::close(to);
    }
    kept.push_back(std::move(copy));
  }
  close_reader();
  if (writer_ >= 0) ::close(writer_);
  writer_ = writer;
  segments_ = std::move(kept);
  cursor_offset_ = 0;
  cursor_records_ = 0;
  front_bytes_ = 0;
  cursor_moved_ = true;
  dirty_ = writer_ >= 0;
  stats_.dropped_lost += lost;
  stats_.bytes = 0;
  stats_.records = 0;
  for (const Segment& s : segments_) {
    stats_.bytes += s.bytes;
    stats_.records += s.records;
  }
  ++files_;  // positions taken in the old files are released no more
  rewind();
  read_high_ = read_;
  find_oldest();
  note("the directory was deleted or moved away: made again; " +
       plural(carried, "change", "changes") +
       " not yet sent carried over from the files still open" +
       (lost != 0 ? ", " + plural(lost, "change", "changes") + " lost with the others" : ""));
  return {};
}

std::error_code Spool::append(std::uint64_t stored_ms, std::string_view bytes) {
  if (bytes.size() > kMaxRecord) return std::make_error_code(std::errc::message_size);
  const std::uint64_t size = kHeader + bytes.size();
  // A segment is appended to by this process only: one left by a run before is not reopened.
  if (writer_ < 0 || segments_.empty() || segments_.back().bytes + size > limits_.segment_bytes) {
    if (writer_ >= 0 && dirty_) ::fdatasync(writer_);  // the old one complete before the new
    dirty_ = false;
    std::error_code ec = start_segment();
    if (ec == std::errc::no_such_file_or_directory && dir_moved() && !recover()) {
      ec = start_segment();
    }
    if (ec) {
      ++stats_.refused;
      return ec;
    }
  }
  std::array<std::uint8_t, kHeader> h{};
  put_le(h.data(), bytes.size(), 4);
  put_le(h.data() + 8, stored_ms, 8);
  put_le(h.data() + 4, record_crc(h.data() + 8, bytes), 4);
  Segment& back = segments_.back();
  const std::string_view header(reinterpret_cast<const char*>(h.data()), h.size());
  std::error_code ec = write_all(writer_, header);
  if (!ec) ec = write_all(writer_, bytes);
  if (ec) {
    // What was written of it is cut off again, so the next record starts on a boundary.
    if (::ftruncate(writer_, static_cast<off_t>(back.bytes)) != 0) {
      ::close(writer_);
      writer_ = -1;  // the next append starts a new segment
    }
    ++stats_.refused;
    return ec;
  }
  back.bytes += size;
  ++back.records;
  dirty_ = true;
  if (stats_.records == 0) stats_.oldest_ms = stored_ms;
  stats_.bytes += size;
  ++stats_.records;
  ++stats_.appended;
  trim_to_size();
  return {};
}

void Spool::trim_to_size() {
  // Whole segments, oldest first; the one being written stays.
  bool trimmed = false;
  while (stats_.bytes > limits_.max_bytes && segments_.size() > 1) {
    stats_.dropped_size += segments_.front().records - cursor_records_;
    drop_front_segment();
    trimmed = true;
  }
  if (trimmed) find_oldest();
}

// The front segment goes, whatever of it was not released; reading goes on after it.
void Spool::drop_front_segment() {
  const Segment& s = segments_.front();
  const std::uint64_t id = s.id;
  stats_.bytes -= s.bytes - cursor_offset_;
  stats_.records -= s.records - cursor_records_;
  if (reader_id_ == id) close_reader();
  ::unlinkat(dir_fd_, name_of(id).c_str(), 0);
  segments_.pop_front();
  cursor_offset_ = 0;
  cursor_records_ = 0;
  cursor_moved_ = true;
  if (read_.segment <= id) {
    read_ = {segments_.empty() ? id + 1 : segments_.front().id, 0, 0, files_};
    front_bytes_ = 0;
  }
  stats_.oldest_ms.reset();
}

void Spool::find_oldest() {
  stats_.oldest_ms.reset();
  if (stats_.records == 0) return;
  std::uint64_t at = cursor_offset_;
  for (const Segment& s : segments_) {
    at = s.skip(at);
    if (at < s.bytes) {
      std::string why;
      const int fd = open_regular_file(dir_fd_, name_of(s.id), O_RDONLY, Links::refuse, why);
      if (fd < 0) return;  // front() finds out why, and says it
      std::array<std::uint8_t, kHeader> h{};
      if (read_exact(fd, h.data(), h.size(), at)) stats_.oldest_ms = get_le(h.data() + 8, 8);
      ::close(fd);
      return;
    }
    at = 0;
  }
}

// The front segment cannot be read on (its file gone, replaced, or damaged since it was
// scanned): what it held that was not taken is lost, counted and said; the file, if there is
// one, is set aside for a human; the queue goes on with the next segment.
void Spool::lose_front_segment(const std::string& why) {
  const Segment& s = segments_.front();
  const std::string name = name_of(s.id);
  stats_.dropped_lost += s.records - cursor_records_;
  std::string lost = plural(s.records - cursor_records_, "change", "changes") + " not yet sent";
  struct stat st {};
  if (::fstatat(dir_fd_, name.c_str(), &st, AT_SYMLINK_NOFOLLOW) == 0) {
    set_aside(name, why + "; " + lost + " in it lost");
  } else {
    note(name + ": " + why + "; " + lost + " lost with it");
  }
  if (segments_.size() == 1 &&
      writer_ >= 0) {  // the one being written: the next append starts anew
    ::close(writer_);
    writer_ = -1;
  }
  drop_front_segment();
}

void Spool::close_reader() {
  if (reader_ >= 0) ::close(reader_);
  reader_ = -1;
}

std::optional<SpoolRecord> Spool::front(std::uint64_t now_ms, std::error_code& error) {
  error.clear();
  while (!segments_.empty()) {
    if (read_.segment < segments_.front().id) rewind();  // its segment went (trimmed)
    const auto seg = std::find_if(segments_.begin(), segments_.end(),
                                  [&](const Segment& x) { return x.id == read_.segment; });
    if (seg == segments_.end()) return std::nullopt;  // past the last: nothing appended yet
    const Segment& s = *seg;
    if (read_.offset >= s.bytes) {
      if (std::next(seg) == segments_.end()) return std::nullopt;  // the one being written
      read_ = {std::next(seg)->id, 0, 0, files_};
      continue;
    }
    // A segment that cannot be read on is given up once reading is at the cursor in it: what was
    // taken before it must be released first, or it would be counted lost as well as sent.
    const bool at_cursor = s.id == segments_.front().id && read_.offset == cursor_offset_;
    if (reader_ < 0 || reader_id_ != s.id) {
      close_reader();
      std::string why;
      reader_ = open_regular_file(dir_fd_, name_of(s.id), O_RDONLY, Links::refuse, why);
      if (reader_ < 0) {
        if (errno == ENOENT && dir_moved()) {
          if (const auto ec = recover()) {
            error = ec;
            return std::nullopt;
          }
          continue;
        }
        if (!at_cursor) return std::nullopt;
        lose_front_segment(after_name(why));
        continue;
      }
      reader_id_ = s.id;
    }
    const std::uint64_t at = s.skip(read_.offset);
    std::array<std::uint8_t, kHeader> h{};
    SpoolRecord r;
    const auto length = read_exact(reader_, h.data(), h.size(), at)
                            ? static_cast<std::uint32_t>(get_le(h.data(), 4))
                            : kMaxRecord + 1;
    if (length <= kMaxRecord) r.bytes.resize(length);
    if (length > kMaxRecord || at + kHeader + length > s.bytes ||
        !read_exact(reader_, r.bytes.data(), length, at + kHeader) ||
        record_crc(h.data() + 8, r.bytes) != get_le(h.data() + 4, 4)) {
      if (!at_cursor) return std::nullopt;
      lose_front_segment("a record damaged since it was written");
      continue;
    }
    r.stored_ms = get_le(h.data() + 8, 8);
    front_bytes_ = at - read_.offset + kHeader + length;
    const auto age = std::chrono::milliseconds(now_ms > r.stored_ms ? now_ms - r.stored_ms : 0);
    if (now_ms != 0 && age > limits_.max_age) {
      // Passed over like a record taken (released with the ones around it), counted once: a
      // rewind reads it again.
      if (!before(read_, read_high_)) ++stats_.dropped_age;
      --stats_.taken;
      take();
      continue;
    }
    return r;
  }
  return std::nullopt;
}

void Spool::take() {
  if (front_bytes_ == 0 || segments_.empty()) return;
  read_.offset += front_bytes_;
  ++read_.records;
  ++stats_.taken;
  front_bytes_ = 0;
  if (before(read_high_, read_)) read_high_ = read_;
}

SpoolPosition Spool::position() const {
  return read_;
}

void Spool::release(const SpoolPosition& p) {
  // Segments wholly before it go; never the one being written, nor past what was read, nor by a
  // position in files made again since.
  if (p.files != files_ || before(read_, p)) return;
  while (segments_.size() > 1 && segments_.front().id < p.segment) drop_front_segment();
  if (segments_.empty() || segments_.front().id != p.segment || p.offset <= cursor_offset_) {
    find_oldest();
    return;
  }
  stats_.bytes -= p.offset - cursor_offset_;
  stats_.records -= p.records - cursor_records_;
  cursor_offset_ = p.offset;
  cursor_records_ = p.records;
  cursor_moved_ = true;
  if (cursor_offset_ >= segments_.front().bytes && segments_.size() > 1) drop_front_segment();
  find_oldest();
}

void Spool::rewind() {
  read_ = {segments_.empty() ? 0 : segments_.front().id, cursor_offset_, cursor_records_, files_};
  front_bytes_ = 0;
}

void Spool::pop() {
  if (front_bytes_ == 0 || segments_.empty()) return;
  take();
  release(read_);
}

std::uint64_t Spool::taken_unreleased() const {
  // Reading is still before the first segment (none existed when it was last set): none taken.
  if (segments_.empty() || read_.segment < segments_.front().id) return 0;
  std::uint64_t n = 0;
  std::uint64_t from = cursor_records_;
  for (const Segment& s : segments_) {
    if (s.id == read_.segment) return n + read_.records - std::min(from, read_.records);
    n += s.records - from;
    from = 0;
  }
  return n;
}

std::error_code Spool::sync() {
  if (dir_fd_ < 0) return std::make_error_code(std::errc::bad_file_descriptor);
  if (dir_moved()) {
    if (auto ec = recover()) return ec;
  }
  if (writer_ >= 0 && dirty_ && ::fdatasync(writer_) != 0) return last_error();
  dirty_ = false;
  if (!cursor_moved_) return {};
  if (segments_.empty()) {
    if (::unlinkat(dir_fd_, kCursor, 0) != 0 && errno != ENOENT) return last_error();
    cursor_moved_ = false;
    return {};
  }
  std::array<char, 64> text{};
  const int n = std::snprintf(text.data(), text.size(), "%016llx %llu\n",
                              static_cast<unsigned long long>(segments_.front().id),
                              static_cast<unsigned long long>(cursor_offset_));
  if (auto ec = replace_file_at(dir_fd_, kCursor,
                                std::string_view(text.data(), static_cast<std::size_t>(n)))) {
    return ec;
  }
  cursor_moved_ = false;
  return {};
}

}  // namespace drivegate::mqtt
