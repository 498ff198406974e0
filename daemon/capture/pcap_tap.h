// A capture in progress on one line: a FrameTap (bus/frame_tap.h) that turns each frame into a
// pcap record (capture/pcap_format.h) and keeps the bytes until the stream takes them. Bounded:
// past `max_bytes` in all it records nothing more and says it is full. No I/O of its own.
#pragma once

#include <chrono>
#include <functional>
#include <string>
#include <unordered_map>

#include "bus/frame_tap.h"

namespace drivegate::capture {

// Who a station is, as the pseudo-header names it.
struct StationInfo {
  std::string adapter;
  std::string device;
  std::uint8_t unit_id = 0;
};

class PcapTap final : public FrameTap {
 public:
  // `steady_ref` and `unix_ref_us` are the same instant on the engine's clock and the wall clock:
  // frames are stamped wall-clock from them. `on_data` is called after each record is added (and
  // once when it becomes full); it may take() but must not remove the tap from the engine.
  PcapTap(std::unordered_map<const Station*, StationInfo> stations, TimePoint steady_ref,
          std::int64_t unix_ref_us, std::size_t max_bytes, std::function<void()> on_data);

  void on_frame(const TappedFrame& frame, TimePoint at) override;

  // The pcap bytes not taken yet (the global header first), moved out.
  std::string take();
  [[nodiscard]] bool full() const { return full_; }
  [[nodiscard]] std::size_t total_bytes() const { return total_; }
  [[nodiscard]] std::size_t frames() const { return frames_; }

 private:
  std::unordered_map<const Station*, StationInfo> stations_;
  TimePoint steady_ref_;
  std::int64_t unix_ref_us_;
  std::size_t max_bytes_;
  std::function<void()> on_data_;
  std::string pending_;
  std::size_t total_ = 0;
  std::size_t frames_ = 0;
  bool full_ = false;
};

}  // namespace drivegate::capture
