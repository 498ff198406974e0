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

bool before(const SpoolPosition& a, const SpoolPosition& b) {
  return a.segment < b.segment || (a.segment == b.segment && a.offset < b.offset);
}

std::optional<std::uint64_t> segment_id(const fs::path& p) {
  const std::string name = p.filename().string();
  if (p.extension() != ".seg" || name.size() != 20) return std::nullopt;
  std::uint64_t id = 0;
  const auto [end, ec] = std::from_chars(name.data(), name.data() + 16, id, 16);
  if (ec != std::errc() || end != name.data() + 16) return std::nullopt;
  return id;
}

}  // namespace

std::uint32_t crc32_ieee(std::string_view bytes, std::uint32_t crc) {
  crc = ~crc;
  for (const char ch : bytes) {
    crc = kCrcTable[(crc ^ static_cast<std::uint8_t>(ch)) & 0xFFU] ^ (crc >> 8);
  }
  return ~crc;
}

Spool::Spool(std::filesystem::path dir, SpoolLimits limits)
    : dir_(std::move(dir)), limits_(limits) {
  if (limits_.segment_bytes == 0) {
    limits_.segment_bytes = std::max<std::uint64_t>(limits_.max_bytes / 16, 4096);
  }
}

Spool::~Spool() {
  close_reader();
  if (writer_ >= 0) ::close(writer_);
}

fs::path Spool::path_of(std::uint64_t id) const {
  std::array<char, 17> hex{};
  std::snprintf(hex.data(), hex.size(), "%016llx", static_cast<unsigned long long>(id));
  return dir_ / (std::string(hex.data()) + ".seg");
}

std::error_code Spool::open() {
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec) return ec;
  std::vector<std::uint64_t> ids;
  for (const auto& e : fs::directory_iterator(dir_, ec)) {
    if (const auto id = segment_id(e.path()); id && e.is_regular_file()) ids.push_back(*id);
  }
  if (ec) return ec;
  std::sort(ids.begin(), ids.end());
  for (const std::uint64_t id : ids) {
    Segment s{id, 0, 0};
    if (auto e = scan(s)) return e;
    segments_.push_back(s);
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

// Counts a segment's records; a record cut short or damaged ends it (the file is truncated).
std::error_code Spool::scan(Segment& s) {
  const fs::path p = path_of(s.id);
  const int fd = ::open(p.c_str(), O_RDWR | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) return last_error();
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const auto e = last_error();
    ::close(fd);
    return e;
  }
  const auto size = static_cast<std::uint64_t>(st.st_size);
  std::uint64_t at = 0;
  std::string body;
  while (at + kHeader <= size) {
    std::array<std::uint8_t, kHeader> h{};
    if (!read_exact(fd, h.data(), h.size(), at)) break;
    const auto length = static_cast<std::uint32_t>(get_le(h.data(), 4));
    const auto crc = static_cast<std::uint32_t>(get_le(h.data() + 4, 4));
    if (length > kMaxRecord || at + kHeader + length > size) break;
    body.resize(length);
    if (!read_exact(fd, body.data(), length, at + kHeader)) break;
    if (record_crc(h.data() + 8, body) != crc) break;
    at += kHeader + length;
    ++s.records;
  }
  if (at < size) {
    stats_.dropped_corrupt += size - at;
    if (::ftruncate(fd, static_cast<off_t>(at)) != 0) {
      const auto e = last_error();
      ::close(fd);
      return e;
    }
  }
  s.bytes = at;
  ::close(fd);
  return {};
}

// "<segment> <offset>\n", believed only when it names a record boundary of a kept segment
// (checked by walking that segment's headers); else everything kept is replayed.
void Spool::read_cursor() {
  std::string error;
  const auto text = read_regular_file(dir_ / "cursor", 256, error);
  if (!text || segments_.empty()) return;
  std::uint64_t id = 0;
  std::uint64_t offset = 0;
  const char* p = text->data();
  const char* end = p + text->size();
  auto r = std::from_chars(p, end, id, 16);
  if (r.ec != std::errc() || r.ptr == end || *r.ptr != ' ') return;
  r = std::from_chars(r.ptr + 1, end, offset);
  if (r.ec != std::errc()) return;
  const auto seg = std::find_if(segments_.begin(), segments_.end(),
                                [&](const Segment& s) { return s.id == id; });
  if (seg == segments_.end() || offset > seg->bytes) return;
  const int fd = ::open(path_of(id).c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) return;
  std::uint64_t at = 0;
  std::uint64_t records = 0;
  while (at < offset) {
    std::array<std::uint8_t, kHeader> h{};
    if (!read_exact(fd, h.data(), h.size(), at)) break;
    at += kHeader + get_le(h.data(), 4);
    ++records;
  }
  ::close(fd);
  if (at != offset) return;
  // The segments before the cursor's were taken whole: gone.
  while (segments_.front().id != id) {
    std::error_code ec;
    fs::remove(path_of(segments_.front().id), ec);
    segments_.pop_front();
  }
  cursor_offset_ = offset;
  cursor_records_ = records;
}

std::error_code Spool::start_segment() {
  if (writer_ >= 0) ::close(writer_);
  writer_ = -1;
  const std::uint64_t id = segments_.empty() ? 1 : segments_.back().id + 1;
  const int fd = ::open(path_of(id).c_str(),
                        O_WRONLY | O_CREAT | O_EXCL | O_APPEND | O_CLOEXEC | O_NOFOLLOW, 0600);
  if (fd < 0) return last_error();
  writer_ = fd;
  segments_.push_back({id, 0, 0});
  return {};
}

std::error_code Spool::append(std::uint64_t stored_ms, std::string_view bytes) {
  if (bytes.size() > kMaxRecord) return std::make_error_code(std::errc::message_size);
  const std::uint64_t size = kHeader + bytes.size();
  // A segment is appended to by this process only: one left by a run before is not reopened.
  if (writer_ < 0 || segments_.empty() || segments_.back().bytes + size > limits_.segment_bytes) {
    if (writer_ >= 0 && dirty_) ::fdatasync(writer_);  // the old one complete before the new
    dirty_ = false;
    if (auto ec = start_segment()) {
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
  std::error_code ec;
  fs::remove(path_of(id), ec);
  segments_.pop_front();
  cursor_offset_ = 0;
  cursor_records_ = 0;
  cursor_moved_ = true;
  if (read_.segment <= id) {
    read_ = {segments_.empty() ? id + 1 : segments_.front().id, 0, 0};
    front_bytes_ = 0;
  }
  stats_.oldest_ms.reset();
}

void Spool::find_oldest() {
  stats_.oldest_ms.reset();
  if (stats_.records == 0) return;
  std::uint64_t at = cursor_offset_;
  for (const Segment& s : segments_) {
    if (at < s.bytes) {
      const int fd = ::open(path_of(s.id).c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
      if (fd < 0) return;
      std::array<std::uint8_t, kHeader> h{};
      if (read_exact(fd, h.data(), h.size(), at)) stats_.oldest_ms = get_le(h.data() + 8, 8);
      ::close(fd);
      return;
    }
    at = 0;
  }
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
      read_ = {std::next(seg)->id, 0, 0};
      continue;
    }
    if (reader_ < 0 || reader_id_ != s.id) {
      close_reader();
      reader_ = ::open(path_of(s.id).c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
      if (reader_ < 0) {
        error = last_error();
        return std::nullopt;
      }
      reader_id_ = s.id;
    }
    std::array<std::uint8_t, kHeader> h{};
    SpoolRecord r;
    const auto length = read_exact(reader_, h.data(), h.size(), read_.offset)
                            ? static_cast<std::uint32_t>(get_le(h.data(), 4))
                            : kMaxRecord + 1;
    if (length <= kMaxRecord) r.bytes.resize(length);
    if (length > kMaxRecord ||
        !read_exact(reader_, r.bytes.data(), length, read_.offset + kHeader)) {
      error = std::make_error_code(std::errc::io_error);
      return std::nullopt;
    }
    r.stored_ms = get_le(h.data() + 8, 8);
    front_bytes_ = kHeader + length;
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
  // Segments wholly before it go; never the one being written, nor past what was read.
  if (before(read_, p)) return;
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
  read_ = {segments_.empty() ? 0 : segments_.front().id, cursor_offset_, cursor_records_};
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
  if (writer_ >= 0 && dirty_ && ::fdatasync(writer_) != 0) return last_error();
  dirty_ = false;
  if (!cursor_moved_) return {};
  if (segments_.empty()) {
    std::error_code ec;
    fs::remove(dir_ / "cursor", ec);
    cursor_moved_ = false;
    return ec;
  }
  std::array<char, 64> text{};
  const int n = std::snprintf(text.data(), text.size(), "%016llx %llu\n",
                              static_cast<unsigned long long>(segments_.front().id),
                              static_cast<unsigned long long>(cursor_offset_));
  if (auto ec = replace_file(dir_ / "cursor",
                             std::string_view(text.data(), static_cast<std::size_t>(n)))) {
    return ec;
  }
  cursor_moved_ = false;
  return {};
}

}  // namespace drivegate::mqtt
