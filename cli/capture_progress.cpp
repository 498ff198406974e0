#include "capture_progress.h"

#include <algorithm>

namespace drivegate::cli {

namespace {
constexpr std::size_t kRecordHeader = 16;
}

void PcapCounter::feed(std::string_view bytes) {
  bytes_ += bytes.size();
  while (!bytes.empty()) {
    if (skip_ > 0) {
      const std::size_t n = std::min(skip_, bytes.size());
      skip_ -= n;
      bytes.remove_prefix(n);
      continue;
    }
    const std::size_t n = std::min(kRecordHeader - header_.size(), bytes.size());
    header_.append(bytes.substr(0, n));
    bytes.remove_prefix(n);
    if (header_.size() < kRecordHeader) break;
    std::size_t length = 0;
    for (int i = 3; i >= 0; --i) {
      length = length * 256 + static_cast<unsigned char>(header_[8 + static_cast<std::size_t>(i)]);
    }
    header_.clear();
    skip_ = length;
    ++frames_;
  }
}

CaptureProgress::CaptureProgress(std::ostream& out, bool in_place, std::string bus,
                                 std::chrono::seconds length)
    : out_(out), in_place_(in_place), bus_(std::move(bus)), length_(length) {}

void CaptureProgress::started(Clock::time_point now) {
  started_ = now;
  drawn_ = now;
  running_ = true;
  draw(now);
}

void CaptureProgress::tick(Clock::time_point now) {
  if (running_ && now - drawn_ >= std::chrono::seconds(1)) draw(now);
}

void CaptureProgress::finish(Clock::time_point now, bool ended) {
  if (!running_) return;
  draw(now, ended);
  running_ = false;
  if (in_place_) out_ << "\n" << std::flush;
}

void CaptureProgress::draw(Clock::time_point now, bool ended) {
  // Whole seconds left, rounded up: "1 s left" until the very end.
  const auto elapsed = std::chrono::duration_cast<std::chrono::milliseconds>(now - started_);
  const auto left_ms = ended ? 0 : std::max<std::int64_t>(0, (length_ - elapsed).count());
  const auto left_s = (left_ms + 999) / 1000;
  const std::uint64_t frames = counter_.frames();
  out_ << (in_place_ ? "\r" : "") << "drivegate capture: bus " << bus_ << ": " << frames
       << (frames == 1 ? " frame, " : " frames, ") << counter_.bytes() << " bytes, " << left_s
       << " s left" << (in_place_ ? "\033[K" : "\n") << std::flush;
  drawn_ = now;
}

}  // namespace drivegate::cli
