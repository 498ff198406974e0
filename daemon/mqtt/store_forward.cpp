#include "mqtt/store_forward.h"

#include <algorithm>

#include "mqtt/sparkplug.h"
#include "mqtt/sparkplug_codec.h"

namespace drivegate::mqtt {

std::string encode_record(std::string_view device, const sparkplug::Payload& payload) {
  std::string out;
  const auto n = static_cast<std::uint16_t>(std::min<std::size_t>(device.size(), 0xFFFF));
  out.push_back(static_cast<char>(n & 0xFF));
  out.push_back(static_cast<char>(n >> 8));
  out.append(device.substr(0, n));
  out += sparkplug::encode(payload);
  return out;
}

std::optional<StoredChange> decode_record(std::string_view bytes) {
  if (bytes.size() < 2) return std::nullopt;
  const std::size_t n = static_cast<std::uint8_t>(bytes[0]) |
                        static_cast<std::size_t>(static_cast<std::uint8_t>(bytes[1])) << 8;
  if (bytes.size() < 2 + n || n == 0) return std::nullopt;
  std::string why;
  auto payload = sparkplug::decode(bytes.substr(2 + n), why);
  if (!payload) return std::nullopt;
  return StoredChange{std::string(bytes.substr(2, n)), std::move(*payload)};
}

StoreForward::StoreForward(std::filesystem::path dir, SpoolLimits limits, unsigned per_second,
                           std::shared_ptr<spdlog::logger> log)
    : spool_(dir, limits,
             [log, dir](const std::string& what) {
               log->warn("MQTT: store and forward: {}: {}", dir.string(), what);
             }),
      batch_(std::max(1U, per_second / 10)),
      max_window_(std::max(1U, per_second)),
      log_(std::move(log)) {}

bool StoreForward::open() {
  if (const auto ec = spool_.open()) {
    log_->error("MQTT: store and forward off: {}: {}", spool_.dir().string(), ec.message());
    return false;
  }
  const SpoolStats& s = spool_.stats();
  if (s.records != 0) {
    log_->info("MQTT: {} changes kept from before ({} bytes) will be sent once a session is online",
               s.records, s.bytes);
  }
  return true;
}

void StoreForward::keep(std::string_view device, const sparkplug::Payload& historical,
                        std::uint64_t now_ms) {
  if (const auto ec = spool_.append(now_ms, encode_record(device, historical))) {
    if (!failing_) {
      log_->error("MQTT: cannot keep a change for later in {}: {}; changes are lost until it can",
                  spool_.dir().string(), ec.message());
    }
    failing_ = true;
    return;
  }
  if (failing_) log_->info("MQTT: {}: changes are kept again", spool_.dir().string());
  failing_ = false;
}

unsigned StoreForward::replay(sparkplug::EdgeNode& edge, sparkplug::Sink& sink,
                              const sparkplug::Now& now, unsigned max) {
  using sparkplug::EdgeNode;
  unsigned taken = 0;
  for (; taken < (max == 0 ? batch_ : max) && !window_full(); ++taken) {
    std::error_code ec;
    const auto r = spool_.front(now.unix_ms, ec);
    if (!r) {
      if (ec && !read_failing_) {
        log_->error("MQTT: cannot read the changes kept in {}: {}; they wait until it can",
                    spool_.dir().string(), ec.message());
      }
      read_failing_ = static_cast<bool>(ec);
      break;
    }
    read_failing_ = false;
    auto change = decode_record(r->bytes);
    if (!change) {  // the CRC held, so only a bug could get here: never stop the queue on it
      ++unreadable_;
      spool_.take();
      continue;
    }
    replaying_ = true;
    replay_number_.reset();
    const auto outcome = edge.replay(change->device, std::move(change->payload), now, sink);
    replaying_ = false;
    if (outcome == EdgeNode::Replay::not_now) break;  // offline again, refused, waiting: kept
    spool_.take();
    if (outcome == EdgeNode::Replay::sent && replay_number_) {
      unconfirmed_.push_back({*replay_number_, spool_.position(), {}, {}});
      ++records_out_;
    } else if (outcome == EdgeNode::Replay::sent) {
      ++replayed_;  // a sink that does not say what the client took: nothing to wait for
    }
  }
  release_settled();
  return taken;
}

void StoreForward::sent(std::uint64_t number, std::string_view topic,
                        const sparkplug::Payload& payload) {
  if (replaying_) {
    replay_number_ = number;
    return;
  }
  const auto t = sparkplug::parse_topic(topic);
  if (!t) return;
  auto history = sparkplug::as_history(t->type, payload);
  if (!history) return;
  unconfirmed_.push_back({number, std::nullopt, t->device, std::move(*history)});
}

void StoreForward::delivered(std::uint64_t number) {
  bool released = false;
  while (!unconfirmed_.empty() && unconfirmed_.front().number <= number) {
    if (const auto& at = unconfirmed_.front().replayed) {
      spool_.release(*at);
      ++replayed_;
      --records_out_;
      released = true;
    }
    unconfirmed_.pop_front();
  }
  if (released) window_ = std::min(max_window_, window_ * 2);
  release_settled();
}

void StoreForward::release_settled() {
  if (records_out_ == 0) spool_.release(spool_.position());
}

void StoreForward::lost(std::uint64_t now_ms) {
  spool_.rewind();
  records_out_ = 0;
  window_ = 1;
  for (Unconfirmed& u : unconfirmed_) {
    if (!u.replayed) keep(u.device, u.history, now_ms);
  }
  unconfirmed_.clear();
}

void StoreForward::sync() {
  const auto ec = spool_.sync();
  if (ec && !sync_failing_) {
    log_->warn("MQTT: {}: cannot sync: {}; said again only after it could", spool_.dir().string(),
               ec.message());
  } else if (!ec && sync_failing_) {
    log_->info("MQTT: {}: synced again", spool_.dir().string());
  }
  sync_failing_ = static_cast<bool>(ec);
}

StoreStats StoreForward::stats(const sparkplug::EdgeNode& edge) const {
  const SpoolStats& s = spool_.stats();
  StoreStats out;
  out.enabled = true;
  out.records = s.records;
  out.bytes = s.bytes;
  out.oldest_ms = s.oldest_ms;
  out.kept = s.appended;
  out.replayed = replayed_;
  out.dropped_size = s.dropped_size;
  out.dropped_age = s.dropped_age;
  out.dropped_corrupt = s.dropped_corrupt;
  out.dropped_lost = s.dropped_lost;
  out.refused = s.refused;
  out.replay_dropped = unreadable_ + edge.replay_dropped();
  return out;
}

}  // namespace drivegate::mqtt
