#include "scan.h"

#include <algorithm>
#include <array>
#include <bitset>
#include <charconv>
#include <utility>

#include "line_timing.h"
#include "presence_probe.h"

namespace drivegate::modbus_device {
namespace {

Bytes probe_pdu() {
  return {kPresenceProbe.begin(), kPresenceProbe.end()};
}
// The basic category is three objects (Application Protocol 6.21); a slave that sends one object
// a reply at least, as each reply must, needs at most three requests for them.
constexpr int kMaxIdentityRequests = 3;
// Each request is sent again once where a second try can change the outcome: an identification
// (the slave is known to be there), and a probe that drew damaged bytes (something answered).
// A silent probe is not: a scan of 247 addresses stays within 247 waits.
constexpr int kAttempts = 2;

// A frame's length on the line for a PDU of `pdu` bytes: RTU adds the address and the CRC
// (Serial Line 2.5.1.1), ASCII sends address, PDU and LRC as two characters each between ':'
// and CR LF (2.5.2.1).
constexpr std::size_t frame_size(Framing f, std::size_t pdu) {
  return f == Framing::rtu ? pdu + 3 : 2 * (pdu + 2) + 3;
}

// Surrounding spaces and NULs (a device pads a fixed-size string with either) removed.
std::string_view unpadded(std::string_view s) {
  const auto pad = [](char c) { return c == ' ' || c == '\0'; };
  while (!s.empty() && pad(s.front())) s.remove_prefix(1);
  while (!s.empty() && pad(s.back())) s.remove_suffix(1);
  return s;
}

bool same_ignoring_case(std::string_view a, std::string_view b) {
  const auto lower = [](char c) {
    return c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c;
  };
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(),
                                            [&](char x, char y) { return lower(x) == lower(y); });
}

std::optional<unsigned> slave_number(std::string_view text) {
  unsigned n = 0;
  const auto [p, ec] = std::from_chars(text.data(), text.data() + text.size(), n);
  if (ec != std::errc{} || p != text.data() + text.size() || n < 1 || n > kMaxSlave) {
    return std::nullopt;
  }
  return n;
}

}  // namespace

std::optional<std::vector<std::uint8_t>> parse_addresses(std::string_view text,
                                                         std::string& error) {
  std::bitset<kMaxSlave + 1> wanted;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    const std::string_view part = text.substr(start, comma - start);
    const std::size_t dash = part.find('-');
    const auto from = slave_number(part.substr(0, dash));
    const auto to = dash == std::string_view::npos ? from : slave_number(part.substr(dash + 1));
    if (!from || !to || *from > *to) {
      error = "'" + std::string(part) +
              "' is not an address or a range of them (1..247, as in 1-247 or 1-10,17)";
      return std::nullopt;
    }
    for (unsigned a = *from; a <= *to; ++a) wanted.set(a);
    start = comma + 1;
  }
  std::vector<std::uint8_t> out;
  for (unsigned a = 1; a <= kMaxSlave; ++a) {
    if (wanted.test(a)) out.push_back(static_cast<std::uint8_t>(a));
  }
  return out;
}

std::optional<std::string_view> FoundSlave::object(std::uint8_t id) const {
  for (const auto& o : identity) {
    if (o.id == id) return std::string_view(o.value);
  }
  return std::nullopt;
}

Scanner::Scanner(ScanSettings settings) : settings_(std::move(settings)) {}

ScanRequest Scanner::request(std::uint8_t address, const Bytes& pdu,
                             std::size_t longest_reply) const {
  ScanRequest r;
  r.address = address;
  r.frame = encode(settings_.framing, address, pdu);
  r.gap = inter_frame_gap(settings_.framing, settings_.char_time);
  // The write completes when the kernel has the frame, not when it is on the wire.
  r.wait = wire_time(settings_.char_time, r.frame.size()) + settings_.timeout +
           wire_time(settings_.char_time, longest_reply);
  return r;
}

std::chrono::nanoseconds Scanner::probe_time() const {
  const ScanRequest r =
      request(1, probe_pdu(), frame_size(settings_.framing, kPresenceProbeReplyPdu));
  return r.gap + r.wait;
}

std::chrono::nanoseconds Scanner::answer_time() const {
  const ScanRequest r =
      request(1, device_id_request(DeviceIdCode::basic, 0), longest_frame(settings_.framing));
  return probe_time() + kMaxIdentityRequests * kAttempts * (r.gap + r.wait);
}

std::chrono::nanoseconds Scanner::time_left() const {
  const ScanRequest r =
      request(1, probe_pdu(), frame_size(settings_.framing, kPresenceProbeReplyPdu));
  return static_cast<long>(total() - probed_) * probe_time() +
         (listened_ ? std::chrono::nanoseconds(0) : r.wait);
}

void Scanner::start_probe(std::uint8_t address) {
  asking_ = Asking::probe;
  address_ = address;
  pdu_ = probe_pdu();
  attempt_ = 1;
}

void Scanner::start_identity(std::size_t slave, std::uint8_t first_object) {
  asking_ = Asking::identity;
  slave_ = slave;
  address_ = found_[slave].address;
  first_object_ = first_object;
  pdu_ = device_id_request(DeviceIdCode::basic, first_object);
  attempt_ = 1;
  if (first_object == 0) identity_requests_ = 0;
}

std::optional<ScanRequest> Scanner::next() {
  rx_.clear();
  damaged_ = false;
  if (repeat_) {
    repeat_ = false;
    ++attempt_;
  } else if (follow_up_) {
    start_identity(slave_, *follow_up_);
    follow_up_.reset();
  } else if (!to_identify_.empty()) {
    const std::size_t slave = to_identify_.front();
    to_identify_.erase(to_identify_.begin());
    start_identity(slave, 0);
  } else if (probed_ < total()) {
    start_probe(settings_.addresses[probed_]);
  } else if (!std::exchange(listened_, true) && !silent_.empty() &&
             silent_.back() == settings_.addresses.back()) {
    // The last probe went unanswered: no probe after it will hear a late reply to it, so the
    // line is listened to for as long as one would have.
    asking_ = Asking::late_replies;
    address_ = 0;
    echo_.clear();
    ScanRequest r = request(settings_.addresses.back(), probe_pdu(),
                            frame_size(settings_.framing, kPresenceProbeReplyPdu));
    r.address = 0;
    r.frame.clear();
    r.gap = {};
    return r;
  } else {
    asking_ = Asking::nothing;
    return std::nullopt;
  }
  ScanRequest r =
      asking_ == Asking::probe
          ? request(address_, pdu_, frame_size(settings_.framing, kPresenceProbeReplyPdu))
          : request(address_, pdu_, longest_frame(settings_.framing));
  echo_ = r.frame;
  return r;
}

bool Scanner::on_receive(ByteView bytes) {
  rx_.insert(rx_.end(), bytes.begin(), bytes.end());
  // A line that hears its own request (an RS-485 adapter with its receiver on while it sends):
  // the request's bytes come first, as they went out. A reply differs from its request by its
  // third byte at the latest (6.3: the byte count; 6.21: the conformity level; 7: the
  // function's top bit), so a prefix of the request is waited on, and anything else is a reply.
  if (!echo_.empty()) {
    const std::size_t n = std::min(rx_.size(), echo_.size());
    if (!std::equal(rx_.begin(), rx_.begin() + static_cast<std::ptrdiff_t>(n), echo_.begin())) {
      echo_.clear();
    } else if (n < echo_.size()) {
      return false;
    } else {
      rx_.erase(rx_.begin(), rx_.begin() + static_cast<std::ptrdiff_t>(n));
      echo_.clear();
      ++echoes_;
    }
  }
  while (!rx_.empty()) {
    const auto d = decode_reply(settings_.framing, rx_);
    if (d.status == DecodeStatus::incomplete) break;
    rx_.erase(rx_.begin(), rx_.begin() + static_cast<std::ptrdiff_t>(d.consumed));
    if (d.status == DecodeStatus::bad) {
      damaged_ = true;
      continue;
    }
    if (on_frame(d.frame)) return true;
  }
  return false;
}

bool Scanner::on_frame(const Adu& adu) {
  if (asking_ != Asking::nothing && adu.address == address_ && adu.pdu == pdu_) {
    ++echoes_;  // the request itself, given back after a stray byte hid it from on_receive()
    return false;
  }
  if (asking_ == Asking::nothing || asking_ == Asking::late_replies || adu.address != address_) {
    if (!late_probe_reply(adu)) ++foreign_;
    return false;
  }
  if (asking_ == Asking::identity) return on_identity_reply(adu);
  FoundSlave s;
  s.address = address_;
  s.probe_reply = adu.pdu;
  found_.push_back(std::move(s));
  to_identify_.push_back(found_.size() - 1);
  probe_over();
  return true;
}

bool Scanner::late_probe_reply(const Adu& adu) {
  const std::uint8_t function = adu.pdu.empty() ? 0 : adu.pdu[0];
  if ((function & ~kExceptionBit) != fc::read_holding_registers) return false;
  const auto at = std::lower_bound(silent_.begin(), silent_.end(), adu.address);
  if (at == silent_.end() || *at != adu.address) return false;
  silent_.erase(at);
  FoundSlave s;
  s.address = adu.address;
  s.probe_reply = adu.pdu;
  s.late = true;
  found_.push_back(std::move(s));
  to_identify_.push_back(found_.size() - 1);
  return true;
}

bool Scanner::on_identity_reply(const Adu& adu) {
  FoundSlave& s = found_[slave_];
  const std::uint8_t function = adu.pdu.empty() ? 0 : adu.pdu[0];
  if (function == fc::read_holding_registers ||
      function == (fc::read_holding_registers | kExceptionBit)) {
    return false;  // its probe's reply, late: the identification's may still come
  }
  asking_ = Asking::nothing;
  if (const auto code = exception_code(adu.pdu);
      code && function == (fc::encapsulated_interface | kExceptionBit)) {
    s.identity_status = Identity::refused;
    s.identity_exception = *code;
    return true;
  }
  const auto reply = parse_device_id_reply(adu.pdu);
  if (!reply) {
    s.identity_status = s.identity.empty() ? Identity::bad_reply : Identity::given;
    return true;
  }
  for (const auto& o : reply->objects) {
    if (!s.object(o.id)) s.identity.push_back(o);
  }
  ++identity_requests_;
  // The rest from the object the slave names, as long as it moves on (6.21, "More Follows").
  if (reply->more_follows && reply->next_object > first_object_ &&
      identity_requests_ < kMaxIdentityRequests) {
    follow_up_ = reply->next_object;
  } else {
    s.identity_status = Identity::given;
  }
  return true;
}

void Scanner::probe_over() {
  ++probed_;
  asking_ = Asking::nothing;
}

void Scanner::on_timeout() {
  // Bytes still waiting to make a frame when the wait ran out made none: a reply cut short, or
  // whose byte count says more than came. (A request's echo still coming is not one.)
  if (!rx_.empty() && echo_.empty()) damaged_ = true;
  if (asking_ == Asking::late_replies) {
    asking_ = Asking::nothing;
    return;
  }
  if (asking_ == Asking::probe) {
    if (damaged_ && attempt_ < kAttempts) {
      repeat_ = true;
      return;
    }
    if (damaged_) {
      garbled_.push_back(address_);
    } else {
      silent_.insert(std::lower_bound(silent_.begin(), silent_.end(), address_), address_);
    }
    probe_over();
    return;
  }
  if (asking_ == Asking::identity) {
    if (attempt_ < kAttempts) {
      repeat_ = true;
      return;
    }
    FoundSlave& s = found_[slave_];
    // A follow-up that never came leaves what the first replies gave.
    s.identity_status = !s.identity.empty() ? Identity::given
                        : damaged_          ? Identity::bad_reply
                                            : Identity::no_reply;
    asking_ = Asking::nothing;
  }
}

bool identifies(const ProfileIdentification& want, std::string_view vendor_name,
                std::string_view product_code) {
  if (!same_ignoring_case(unpadded(want.vendor_name), unpadded(vendor_name))) return false;
  std::string_view product = unpadded(want.product_code);
  const std::string_view have = unpadded(product_code);
  if (!product.empty() && product.back() == '*') {
    product.remove_suffix(1);
    return have.size() >= product.size() &&
           same_ignoring_case(have.substr(0, product.size()), product);
  }
  return same_ignoring_case(product, have);
}

}  // namespace drivegate::modbus_device
