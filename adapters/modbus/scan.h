// `drivegate scan`'s search of a Modbus serial line for its slaves, pure: which addresses, what
// request each gets, how long it waits, how a reply is judged, and what each slave found says it
// is. No I/O and no clock: the command (cli/scan_cmd.cpp) asks next(), keeps the request's gap,
// sends its frame, then hands back every byte it reads (on_receive) or that the wait ran out
// (on_timeout), and asks next() again.
//
// A probe is a read of one holding register at address 0 (Application Protocol 6.3): a request
// every slave can judge, so that any good frame from the address, the registers or an exception
// (Application Protocol 7: a slave without that register says 02), means a slave is there. Each
// slave found is then asked for its basic device identification (FC 0x2B / 0x0E, read device id
// code 01: VendorName, ProductCode, MajorMinorRevision; Application Protocol 6.21).
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "codec.h"
#include "device_id.h"
#include "profile.h"

namespace drivegate::modbus_device {

// "1-247", "17", "1-10,17,20-30": slave addresses (1..247, Serial Line 2.2; the broadcast 0
// draws no reply and is never probed), ascending, each once. nullopt with `error` naming the
// part that is wrong.
std::optional<std::vector<std::uint8_t>> parse_addresses(std::string_view text, std::string& error);

struct ScanSettings {
  Framing framing = Framing::rtu;
  std::chrono::nanoseconds char_time{0};   // one character on the line (drivegate/line.h)
  std::chrono::milliseconds timeout{100};  // a slave's time to start its reply
  std::vector<std::uint8_t> addresses;     // parse_addresses()
};

// One request: keep the line silent for `gap`, send `frame`, and give up on the reply `wait`
// after the write completed (the request's and the longest reply's time on the wire included).
// An empty `frame` sends nothing: the line is only listened to for `wait` (after the last probe,
// for a reply that comes after its own wait: a neighbour's probe would have heard it).
struct ScanRequest {
  std::uint8_t address = 0;
  Bytes frame;
  std::chrono::nanoseconds gap{0};
  std::chrono::nanoseconds wait{0};
};

// What came of asking a slave for its identification.
enum class Identity : std::uint8_t {
  pending,    // not asked yet
  given,      // `identity` holds what it said (possibly no object at all)
  refused,    // an exception reply; `identity_exception` says which (01: not supported)
  no_reply,   // silent twice
  bad_reply,  // a good frame, but no well-formed identification
};

struct FoundSlave {
  std::uint8_t address = 0;
  Bytes probe_reply;  // the PDU it answered the probe with: registers or an exception
  bool late = false;  // its reply came after its wait had run out, during a later probe
  Identity identity_status = Identity::pending;
  std::uint8_t identity_exception = 0;
  std::vector<DeviceIdObject> identity;  // in the order the device sent them

  // The value of identification object `id` (device_id.h), if the slave gave it.
  [[nodiscard]] std::optional<std::string_view> object(std::uint8_t id) const;
};

class Scanner {
 public:
  explicit Scanner(ScanSettings settings);

  // The next request, or nullopt when the scan is over. Bytes received until then belong to
  // the request before; an incomplete frame still in the buffer is dropped here (an RTU frame
  // ends in silence, and the gap is longer).
  std::optional<ScanRequest> next();
  // Bytes from the line. True when they end the request in flight (its reply is in): call
  // next() then, without waiting out its time.
  bool on_receive(ByteView bytes);
  // The request in flight had no reply within its wait.
  void on_timeout();

  // The slaves found so far, in the order found.
  [[nodiscard]] const std::vector<FoundSlave>& found() const { return found_; }
  // Addresses where bytes came that made no good frame, and nothing good after them: a line
  // at another baud rate, parity or framing, or two slaves at one address.
  [[nodiscard]] const std::vector<std::uint8_t>& garbled() const { return garbled_; }
  // Good frames from an address that was not asked (another master on the line?).
  [[nodiscard]] std::size_t foreign_frames() const { return foreign_; }
  // Requests the line gave back as they went out (an adapter that hears itself): the bus
  // wants `echo = true`.
  [[nodiscard]] std::size_t echoes() const { return echoes_; }
  // Addresses probed so far, of total().
  [[nodiscard]] std::size_t probed() const { return probed_; }
  [[nodiscard]] std::size_t total() const { return settings_.addresses.size(); }

  // The longest one probe of a silent address takes: its gap and its wait.
  [[nodiscard]] std::chrono::nanoseconds probe_time() const;
  // The most an address that answers adds beyond its probe: one repeated probe (a damaged
  // reply) and every identification request with its one repeat.
  [[nodiscard]] std::chrono::nanoseconds answer_time() const;
  // At most how long the probes still to send take if no other address answers, the last wait
  // for a late reply included.
  [[nodiscard]] std::chrono::nanoseconds time_left() const;

 private:
  enum class Asking : std::uint8_t { nothing, probe, identity, late_replies };
  void start_probe(std::uint8_t address);
  void start_identity(std::size_t slave, std::uint8_t first_object);
  ScanRequest request(std::uint8_t address, const Bytes& pdu, std::size_t longest_reply) const;
  // A good frame while asking: true when it ends the request in flight.
  bool on_frame(const Adu& adu);
  bool on_identity_reply(const Adu& adu);
  void probe_over();
  // A slave's reply to its probe that came too late: found, marked late.
  bool late_probe_reply(const Adu& adu);

  ScanSettings settings_;
  std::vector<FoundSlave> found_;
  std::vector<std::uint8_t> garbled_;
  std::vector<std::uint8_t> silent_;      // addresses whose probe went unanswered, ascending
  std::vector<std::size_t> to_identify_;  // indexes into found_, in the order found
  std::size_t foreign_ = 0;
  std::size_t echoes_ = 0;
  std::size_t probed_ = 0;  // of settings_.addresses
  bool listened_ = false;   // the last wait for a late reply is over (or was not needed)
  Bytes rx_;

  // The request in flight.
  Asking asking_ = Asking::nothing;
  std::uint8_t address_ = 0;
  std::size_t slave_ = 0;  // Asking::identity: index into found_
  Bytes pdu_;              // what was asked, to ask it again
  std::uint8_t first_object_ = 0;
  int attempt_ = 0;                        // 1, or 2 when asked again
  bool damaged_ = false;                   // bytes came that made no good frame
  int identity_requests_ = 0;              // for the slave being identified, follow-ups included
  bool repeat_ = false;                    // next() sends the request in flight again
  std::optional<std::uint8_t> follow_up_;  // next() asks the same slave from this object on
  Bytes echo_;  // the request's frame, until the bytes received differ from it
};

// Whether a slave whose identification says `vendor_name` and `product_code` is the device
// `want` describes: each compared whole, ignoring case and the spaces and NULs a device pads
// fixed-size strings with; a `product_code` ending in '*' matches any product code it starts.
bool identifies(const ProfileIdentification& want, std::string_view vendor_name,
                std::string_view product_code);

}  // namespace drivegate::modbus_device
