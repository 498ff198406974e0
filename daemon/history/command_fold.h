// How the audit trail keeps up with a flood of writes (command_audit.h): which records of the
// clients' writes are written one by one, and which are folded into a summary record instead,
// counted, never dropped. Pure: the caller says what time it is.
//
// A record's key is who wrote what: the source kind, the listener, the client's address (its
// port left out, so a client opening a connection per write is one client), the device, the
// points written (a number's value left out, a label's kept: "setpoint_rpm command=run_forward")
// and the result. Each key writes its records one by one while its allowance lasts (a burst,
// then one more a `refill`); past it the key folds: its records are counted, not written, until
// its summary is due, `interval` after the first folded one, and it folds on while its writes
// keep coming faster than its allowance: one summary an interval. Across all keys, the records
// written one by one have an allowance of their own (`overall_burst`, then `overall_per_second`),
// and at most `keys` keys, `keys_per_client` of one client, are tracked at a time; past those a
// record folds into its client's overflow key (every device and point of the client), or into
// its source kind's (every client of that kind), which summarise it all the same.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include "drivegate/driver.h"
#include "gateway/outcome.h"
#include "gateway/source.h"
#include "net/token_bucket.h"

namespace drivegate {

struct CommandRecord;

struct FoldLimits {
  unsigned burst = 10;                         // one key's records one by one ...
  std::chrono::milliseconds refill{1000};      // ... then one more each
  std::chrono::milliseconds interval{10'000};  // a key's summary this long after its first fold
  unsigned overall_burst = 100;                // all keys' records one by one ...
  unsigned overall_per_second = 10;            // ... then so many a second (1 at least)
  std::size_t keys = 256;                      // keys tracked at a time
  std::size_t keys_per_client = 32;            // ... of one client
};

// Which records a key gathers: one client's writes of some points to one device, or, past the
// tables' bounds, every write of the client or of its source kind (with that result).
enum class FoldSpread : std::uint8_t { points, client, source };

// The records one key folded, to be written as one.
struct FoldSummary {
  FoldSpread spread = FoldSpread::points;
  SourceKind source = SourceKind::modbus;
  std::string listener;  // empty for a source kind's overflow
  std::string client;    // the client's address; empty for a source kind's overflow
  std::string device;    // empty for an overflow
  std::uint8_t unit = 0;
  std::string points;  // as the key has them (fold_points); empty for an overflow
  Outcome result = Outcome::ok;
  std::uint64_t folded = 0;   // how many records
  std::int64_t since_ms = 0;  // the first one's time (ms since the epoch) ...
  std::int64_t last_ms = 0;   // ... and the last one's
  // The last one's own: who exactly (its port, certificate, role), where, what and why.
  Source last_source;
  std::string last_device;
  std::uint8_t last_unit = 0;
  std::string last_points;
  std::string last_why;
};

// A client's address without its port: "192.0.2.7:50122" -> "192.0.2.7", "[::1]:502" -> "[::1]",
// "::1:502" -> "::1"; what has no port ("/dev/ttyS0", an MQTT client id) as it is.
std::string client_address(std::string_view client);
// The points of a record as its key has them: each point's name, with its value if that is a
// label ("setpoint_rpm=1500 command=run_forward" -> "setpoint_rpm command=run_forward");
// registers or a PDU that did not validate by their table or function ("holding 0..1 = 1 1500" ->
// "holding", "pdu 10 00 ..." -> "pdu 10").
std::string fold_points(std::string_view points);

class CommandFold {
 public:
  explicit CommandFold(FoldLimits limits = {});

  // Whether record `r`, at `now` (`wall_ms` on the wall clock), is to be written one by one:
  // false if it was folded, counted in its key's summary.
  bool admit(const CommandRecord& r, TimePoint now, std::int64_t wall_ms);
  // The summaries due at `now` (every one pending, if `all`), oldest first; their keys fold on
  // from a spent allowance. Keys whose allowance is whole again are forgotten.
  std::vector<FoldSummary> due(TimePoint now, bool all = false);
  // Keys tracked now (the bound's test).
  [[nodiscard]] std::size_t keys() const { return keys_.size(); }

 private:
  struct Key {
    FoldSpread spread = FoldSpread::points;
    SourceKind source = SourceKind::modbus;
    std::string listener;
    std::string client;
    std::string device;
    std::uint8_t unit = 0;
    std::string points;
    Outcome result = Outcome::ok;
    // NOLINTNEXTLINE(modernize-use-nullptr): clang-tidy 14 flags a defaulted <=> itself
    auto operator<=>(const Key&) const = default;
  };
  using ClientKey = std::tuple<SourceKind, std::string, std::string>;
  struct Folding {
    TimePoint since{};
    FoldSummary summary;
  };
  struct Entry {
    net::TokenBucket allowance;
    std::optional<Folding> folding;
  };

  // The key `r` counts under now: its own, or an overflow's while the tables are full.
  [[nodiscard]] Key key_for(const CommandRecord& r) const;
  // Forgets the keys with a whole allowance and nothing folded.
  void forget_idle(TimePoint now);

  FoldLimits limits_;
  net::TokenBucket overall_;
  std::map<Key, Entry> keys_;
  std::map<ClientKey, std::size_t> per_client_;  // keys of each client (overflows not counted)
};

}  // namespace drivegate
