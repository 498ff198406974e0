#include "capture/pcap_tap.h"

#include "capture/pcap_format.h"

namespace drivegate::capture {

PcapTap::PcapTap(std::unordered_map<const Station*, StationInfo> stations, TimePoint steady_ref,
                 std::int64_t unix_ref_us, std::size_t max_bytes, std::function<void()> on_data)
    : stations_(std::move(stations)),
      steady_ref_(steady_ref),
      unix_ref_us_(unix_ref_us),
      max_bytes_(max_bytes),
      on_data_(std::move(on_data)),
      pending_(pcap_global_header()),
      total_(pending_.size()) {}

void PcapTap::on_frame(const TappedFrame& frame, TimePoint at) {
  if (full_) return;
  static const StationInfo nobody;
  const auto it = stations_.find(frame.station);
  const StationInfo& who = it == stations_.end() ? nobody : it->second;
  FrameRecord r;
  r.unix_us = unix_ref_us_ +
              std::chrono::duration_cast<std::chrono::microseconds>(at - steady_ref_).count();
  r.direction = static_cast<std::uint8_t>(frame.direction);
  r.flags = frame.flags;
  r.unit_id = who.unit_id;
  r.adapter = who.adapter;
  r.device = who.device;
  r.bytes = frame.bytes;
  std::string record;
  append_pcap_record(record, r);
  if (total_ + record.size() > max_bytes_) {
    full_ = true;
  } else {
    total_ += record.size();
    ++frames_;
    pending_ += record;
  }
  if (on_data_) on_data_();
}

std::string PcapTap::take() {
  std::string out;
  out.swap(pending_);
  return out;
}

}  // namespace drivegate::capture
