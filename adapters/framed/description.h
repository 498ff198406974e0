// A protocol description, as read from its TOML file (description_parser.h) and validated whole:
// the line, the frames and their checks, the messages each way, the variables and points, and how
// the unified block (command, setpoint, status, faults) maps onto them. docs/protocols.md is the
// language; this is its meaning, which the codec (codec.h), the driver (driver.h) and the simulator
// (simulator.h) share. Pure data, plus the compiled expressions.
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "drivegate/common.h"
#include "drivegate/line.h"
#include "drivegate/options.h"
#include "drivegate/point.h"
#include "expression.h"

namespace drivegate::framed {

// The most fields one message may have, and the longest frame a description may declare.
inline constexpr std::size_t kMaxFields = 64;
inline constexpr std::size_t kMaxFrame = 1024;

// ---- the wire --------------------------------------------------------------------------------

// A field's encoding: integers of 1..4 bytes, signed or not, either byte order; packed BCD of 1..4
// bytes (two digits a byte, the most significant first); f32 (IEEE 754) either order.
enum class Encoding : std::uint8_t { unsigned_int, signed_int, bcd, f32 };

// A check's algorithm over a range of the frame (docs/protocols.md, "Checks").
enum class CheckKind : std::uint8_t {
  xor_bytes,        // XOR of the bytes
  sum,              // sum of the bytes, modulo 2^(8 x width)
  sum_to,           // the byte that makes the sum of the range and itself `total`
  twos_complement,  // minus the sum
  lrc,              // Modbus ASCII's LRC: the two's complement of the 8-bit sum
  crc,              // a CRC of 8, 16 or 32 bits by its parameters
};

struct Check {
  std::string name;
  CheckKind kind = CheckKind::xor_bytes;
  std::uint8_t width = 1;  // bytes on the wire
  bool little_endian = false;
  std::uint32_t total = 0;  // sum_to
  // crc: the Rocksoft parameters (poly in normal form).
  std::uint32_t poly = 0;
  std::uint32_t init = 0;
  bool reflect_in = false;
  bool reflect_out = false;
  std::uint32_t xor_out = 0;
  // The range: from byte `from` (negative: from the frame's end) to before `to` (nullopt: the
  // first check of the frame), every `step`-th byte.
  int from = 0;
  std::optional<int> to;
  std::uint8_t step = 1;
  int line = 0;
};

// One token of a layout: a constant byte, a field, or a check.
struct Token {
  enum class Kind : std::uint8_t { constant, field, check };
  Kind kind = Kind::constant;
  std::uint8_t byte = 0;   // constant
  std::size_t offset = 0;  // where it starts in the frame
  std::uint8_t width = 1;  // bytes
  Encoding encoding = Encoding::unsigned_int;
  bool little_endian = false;
  std::size_t field = 0;  // field: index into Message::fields
  std::size_t check = 0;  // check: index into Description::checks
  std::string name;       // check: its name in the layout ("checksum:xor")
};

// How the frames are told apart on the line: by their layouts alone (fixed lengths, constants,
// a length field), or between start and end flags with byte stuffing (docs/protocols.md).
struct Framing {
  std::optional<std::uint8_t> start;
  std::optional<std::uint8_t> end;
  std::optional<std::uint8_t> escape;
  std::vector<std::uint8_t> escaped;  // the bytes sent escaped
  std::uint8_t escape_xor = 0x20;     // an escaped byte is sent as escape, byte ^ escape_xor
  std::size_t max_frame = 256;        // bytes, flags and stuffing included
  [[nodiscard]] bool flagged() const { return start.has_value(); }
};

// A length field: its value is `offset` plus the bytes it counts.
struct Length {
  std::size_t field = 0;  // index into Message::fields
  enum class Counts : std::uint8_t { payload, rest, frame };
  Counts counts = Counts::payload;  // payload: after it, up to the first check
  int offset = 0;
};

enum class Direction : std::uint8_t { request, reply };  // master -> device, device -> master

// An assignment run when a message is received (or sent): `target` (a variable) = `value`.
struct Assign {
  std::size_t target = 0;  // index into Description::vars
  Expr value;
};

struct Field {
  std::string name;
  std::size_t global = 0;  // its name's index in Description::field_names
  Expr value;              // its value when the message is sent (a request; the simulator's reply)
  bool has_value = false;  // given in `values`, or the variable of its name
  std::optional<double> min;  // a received value outside is not this message (a limit)
  std::optional<double> max;
};

struct Message {
  std::string name;
  std::string summary;
  Direction direction = Direction::request;
  std::vector<Token> tokens;
  std::vector<Field> fields;
  std::size_t size = 0;  // bytes before any stuffing
  std::optional<Length> length;
  double length_value = 0;  // what the length field holds (every layout has a fixed size)
  // Received: what it is.
  bool nack = false;           // the device refused the frame: resend
  bool unsolicited = false;    // the device sends it unasked (a stream): applied whenever it comes
  bool state = true;           // it carries the device's state (data_age restarts on it)
  std::vector<Assign> update;  // received (a reply), or sent (a request): applied
  // A reply answers a request when these fields of both are equal (an echoed mode, a sequence).
  std::vector<std::pair<std::size_t, std::size_t>> echo;  // (reply field, request field)
  // A request: the replies that answer it (none: ReplyMode::none, it is never answered).
  std::vector<std::size_t> replies;      // indices into Description::messages
  std::optional<Expr> reply_timeout_ms;  // per attempt; the protocol's otherwise
  std::optional<Expr> attempts;
  int line = 0;
};

// ---- the variables -----------------------------------------------------------------------------

struct Table {
  std::string name;
  std::vector<double> values;  // entry i is the value of i
  int line = 0;
};

// What a name in an expression stands for.
struct Var {
  enum class Kind : std::uint8_t { option, point, state, builtin };
  std::string name;
  Kind kind = Kind::state;
  std::size_t point = 0;             // Kind::point: index into Description::points
  Val initial;                       // state: its value at start
  std::optional<Expr> initial_expr;  // state and points: from the options
  bool reset_on_comm_lost = false;
  Val reset_value;
  int line = 0;
};

// The variables every description has (docs/protocols.md, "The unified block").
namespace builtin {
inline constexpr std::size_t command = 0;   // the command in force (0 stop .. 4 reset_fault)
inline constexpr std::size_t setpoint = 1;  // the setpoint in force, rpm
inline constexpr std::size_t address = 2;   // the device's bus address
inline constexpr std::size_t poll_ms = 3;   // the device's poll interval
inline constexpr std::size_t value = 4;     // the value a point write carries (on_write rules)
inline constexpr std::size_t dt_ms = 5;     // the simulator's: ms since its last tick
inline constexpr std::size_t sequence = 6;  // 0..255, one more for each request made (not resends)
// Constants: the unified commands by name (include/drivegate/common.h), true and false.
inline constexpr std::size_t first_constant = 7;
inline constexpr std::size_t count = first_constant + 7;
}  // namespace builtin

struct Point {
  PointSpec spec;
  std::size_t var = 0;        // its variable
  std::optional<Expr> value;  // derived: recomputed from the others after every update
  // A write to it: stored (done) unless one of these sends a frame.
  struct OnWrite {
    std::optional<Expr> when;
    std::optional<std::size_t> send;  // a request message; none: stored only
    std::optional<Expr> accept;       // on its reply: false refuses
  };
  std::vector<OnWrite> on_write;
  std::optional<std::size_t> status;  // a point told idle 0 / pending 1 / done 2 / no_response 3
  int line = 0;
};

// One of the description's own device options ([device.options] beside `protocol`).
struct Option {
  std::string name;
  OptionType type = OptionType::integer;
  std::string default_text;  // as the core reads defaults: "7", "true", "normal"
  std::string description;
  double min = 0;
  double max = 0;
  std::string choices;  // string: "normal|continuous"
  std::size_t var = 0;
  int line = 0;
};

// ---- behaviour ---------------------------------------------------------------------------------

// A transaction the driver sends by itself: the handshake until it holds (init), or the poll.
struct Periodic {
  std::size_t send = 0;          // request message
  std::optional<Expr> every_ms;  // the period (init: between attempts; 0 at once)
  std::optional<Expr> when;      // sent only while this holds
  bool at_ready = false;         // poll: the first one at once when the device becomes ready
};

// One way to carry out a unified write (a command or a setpoint): the first alternative whose
// `when` holds is taken; when none holds the write is invalid (0x03).
struct Alternative {
  std::optional<Expr> when;
  std::optional<Expr> invalid;      // holds: 0x03
  std::optional<Expr> refuse;       // holds: 0x04, nothing sent
  std::optional<std::size_t> send;  // the request; none: in force at once (done)
  std::optional<Expr> accept;       // on the reply: false refuses (0x04)
  std::optional<Expr> until;      // confirmed once the device's state shows this (a stream, a poll)
  std::optional<Expr> refuse_on;  // while waiting for `until`: the device refused it
  std::optional<Command> becomes;  // the command in force once confirmed; none: unchanged
  bool confirms = false;           // accept or until written (a load-time rule)
  int line = 0;
};

struct Setpoint {
  double min = 0;
  double max = 0;
  bool limited = false;
  // While no run is in force or on its way the setpoint is stored for the next run (done).
  // While one is, the command in force is carried out again at the new setpoint, confirmed by
  // `accept` / `until` here, or by the command's own when these are not given.
  std::optional<Expr> invalid;
  std::optional<Expr> refuse;
  std::optional<Expr> accept;
  std::optional<Expr> until;
  std::optional<Expr> refuse_on;
  int line = 0;
};

struct FaultRule {
  std::optional<Expr> when;  // holds: `fault`
  Fault fault = Fault::other;
  std::optional<Expr> source;  // or: a native value mapped by bits, values or ranges
  std::vector<std::pair<std::uint32_t, Fault>> bits;
  std::vector<std::pair<std::uint32_t, Fault>> values;
  struct Range {
    std::uint32_t lo;
    std::uint32_t hi;
    Fault fault;
  };
  std::vector<Range> ranges;
  std::optional<Fault> other;  // a non-zero value no row names
  int line = 0;
};

struct Unified {
  std::optional<Expr> ready;
  std::optional<Expr> speed_rpm;
  std::optional<Expr> running;  // default: a run in force or speed_rpm != 0
  std::optional<Expr> warning;
  std::optional<Expr> native_fault;
  std::vector<FaultRule> faults;
  // When this holds a run in force is no longer (the drive stopped it: a fault, a brake).
  std::optional<Expr> stops_run;
  bool comm_lost_stops = false;  // the drive stops by itself when the line goes quiet
};

struct Timing {
  Expr reply_timeout_ms = Expr::number(100);
  Expr attempts = Expr::number(3);
  Expr comm_timeout_ms = Expr::number(6000);
  Expr gap_ms = Expr::number(0);
  Expr confirm_ms = Expr::number(2500);  // a write not confirmed by then: 0x0B
  std::optional<double> poll_min_ms;     // the device's poll_ms, clamped
  std::optional<double> poll_max_ms;
  bool writes_wait_for_ready = true;  // false: refused (0x04) until ready
};

struct Simulated {
  // The simulator's own state beside the description's variables: names and initial values;
  // `on` rules answer requests (simulator.h).
  struct Rule {
    std::size_t request = 0;
    std::optional<Expr> when;
    std::optional<std::size_t> reply;  // none: silent
    std::vector<Assign> update;        // on the simulator's variables, before the reply is made
  };
  std::vector<Rule> rules;
  // Sent every `stream_ms` unasked: the first whose `when` holds.
  struct Stream {
    std::optional<Expr> when;
    std::size_t send = 0;
  };
  std::vector<Stream> stream;
  Expr stream_ms = Expr::number(500);
  std::vector<Assign> tick;         // every tick: ramps and the like
  std::optional<std::size_t> nack;  // sent for a frame that fails its check
};

struct Description {
  std::string name;
  std::string summary;
  std::string document;  // the vendor document it follows
  std::string source;    // the file it was read from ("nidec-washer.toml", "shipped ...")

  LineDefaults line{9600, Parity::none, 8, 1, false};
  bool streaming = false;
  std::uint32_t address_min = 0;
  std::uint32_t address_max = 0;
  std::uint32_t address_default = 0;
  std::int32_t demo_rpm = 1000;

  Framing framing;
  std::vector<Check> checks;
  std::vector<Message> messages;
  std::vector<Table> tables;
  std::vector<Var> vars;  // builtin first (builtin::count), then options, points, state
  std::vector<std::string> field_names;  // every field name of every message, once
  std::vector<Point> points;
  std::vector<Option> options;
  std::deque<std::string> texts;  // interned text values (expression literals, string options)

  Timing timing;
  std::optional<Periodic> init;
  std::optional<Periodic> poll;
  std::map<Command, std::vector<Alternative>> commands;
  std::optional<Setpoint> setpoint;
  Unified unified;
  Simulated sim;

  [[nodiscard]] std::optional<std::size_t> message(std::string_view name) const;
  [[nodiscard]] std::optional<std::size_t> var(std::string_view name) const;
  [[nodiscard]] bool has_address() const { return address_max != 0; }
};

}  // namespace drivegate::framed
