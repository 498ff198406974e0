#include "simulator.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <sstream>

#include "drivegate/sim_text.h"
#include "profile_options.h"
#include "values.h"

namespace drivegate::modbus_device {
namespace {

// Exception codes (Application Protocol 7).
constexpr std::uint8_t kIllegalFunction = 0x01;
constexpr std::uint8_t kIllegalAddress = 0x02;
constexpr std::uint8_t kIllegalValue = 0x03;
// A partial request older than this is stale: an RTU frame ends in silence, and a pty delivers
// in bursts.
constexpr Millis kStaleRx{100};

}  // namespace

ModbusSimulator::ModbusSimulator(std::uint8_t address, Profile profile)
    : address_(address), profile_(std::move(profile)), layouts_(write_layouts(profile_)) {
  for (const ProfilePoint& p : profile_.points) {
    for (std::uint16_t w = 0; w < p.width(); ++w) {
      memory_[{p.table, static_cast<std::uint16_t>(p.address + w)}] = 0;
    }
    auto& span = span_[p.table];
    if (span.second == 0 || p.address < span.first) span.first = p.address;
    span.second = std::max<std::uint32_t>(span.second, std::uint32_t{p.address} + p.width());
  }
  drive();
}

// A read may cover the gaps between a table's points (a profile's max_gap reads through them, as
// a real slave's register file allows), not beyond its first and last, nor an address the
// operator made missing.
bool ModbusSimulator::holds(Table table, std::uint32_t start, std::uint32_t count) const {
  const auto it = span_.find(table);
  if (it == span_.end() || start < it->second.first || start + count > it->second.second) {
    return false;
  }
  for (std::uint32_t a = start; a < start + count; ++a) {
    if (missing_.contains({table, static_cast<std::uint16_t>(a)})) return false;
  }
  return true;
}

Bytes ModbusSimulator::on_receive(ByteView rx, TimePoint now) {
  if (last_rx_ && now - *last_rx_ > kStaleRx) rx_.clear();
  last_rx_ = now;
  rx_.insert(rx_.end(), rx.begin(), rx.end());
  Bytes out;
  while (!rx_.empty()) {
    const Decoded<Adu> d = decode_request(profile_.line.framing, rx_, layouts_);
    if (d.status == DecodeStatus::incomplete) break;
    rx_.erase(rx_.begin(), rx_.begin() + static_cast<long>(d.consumed));
    if (d.status == DecodeStatus::bad) continue;  // a slave ignores a frame it cannot check
    if (d.frame.address != address_ && d.frame.address != kBroadcast) continue;
    if (silent_) continue;
    if (every_other_ && heard_++ % 2 == 0) continue;
    const std::optional<Bytes> reply = answer(d.frame.pdu);
    if (!reply || d.frame.address == kBroadcast) continue;  // Serial Line 2.2: not a broadcast
    const Bytes frame = encode(profile_.line.framing, address_, *reply);
    if (late_.count() > 0) {
      due_.emplace_back(now + late_, frame);
    } else {
      out.insert(out.end(), frame.begin(), frame.end());
    }
  }
  return out;
}

Bytes ModbusSimulator::on_tick(TimePoint now) {
  Bytes out;
  while (!due_.empty() && due_.front().first <= now) {
    out.insert(out.end(), due_.front().second.begin(), due_.front().second.end());
    due_.erase(due_.begin());
  }
  return out;
}

std::optional<ModbusSimulator::Range> ModbusSimulator::range_of(ByteView pdu) {
  if (pdu.size() < 5) return std::nullopt;
  const std::uint16_t start = be16(pdu[1], pdu[2]);
  const std::uint16_t count = be16(pdu[3], pdu[4]);
  switch (pdu[0]) {
    case fc::read_coils:
      return Range{Table::coil, start, count};
    case fc::read_discrete_inputs:
      return Range{Table::discrete, start, count};
    case fc::read_holding_registers:
    case fc::write_multiple_registers:
      return Range{Table::holding, start, count};
    case fc::read_input_registers:
      return Range{Table::input, start, count};
    case fc::write_single_coil:
      return Range{Table::coil, start, 1};
    case fc::write_single_register:
      return Range{Table::holding, start, 1};
    default:
      return std::nullopt;
  }
}

std::optional<Bytes> ModbusSimulator::answer(ByteView request) {
  const auto own = std::find_if(layouts_.begin(), layouts_.end(),
                                [&](const CodeLayout& l) { return l.code == request[0]; });
  if (own == layouts_.end()) return answer_laid_out(request);
  Bytes pdu(request.begin(), request.end());
  pdu[0] = own->like;
  // The code writes the registers of the points that name it, and no other (illegal function).
  const auto range = range_of(pdu);
  const bool its_own =
      range &&
      std::any_of(profile_.points.begin(), profile_.points.end(), [&](const ProfilePoint& p) {
        return p.write_code == own->code && p.table == range->table && p.address == range->start;
      });
  if (!its_own) return exception_pdu(request[0], kIllegalFunction);
  auto reply = answer_laid_out(pdu);
  if (reply && !reply->empty() && !reply_as_layout_) {
    (*reply)[0] = static_cast<std::uint8_t>(((*reply)[0] & kExceptionBit) | own->code);
  }
  return reply;
}

std::optional<Bytes> ModbusSimulator::answer_laid_out(ByteView pdu) {
  const auto range = range_of(pdu);
  if (range) {
    for (const Key& k : mute_) {
      if (range->covers(k)) return std::nullopt;
    }
    for (auto it = refused_.begin(); it != refused_.end(); ++it) {
      if (!range->covers(it->first)) continue;
      const std::uint8_t code = it->second.first;
      if (--it->second.second == 0) refused_.erase(it);
      return exception_pdu(pdu[0], code);
    }
  }
  Bytes reply = handle(pdu);
  const bool read = pdu[0] >= fc::read_coils && pdu[0] <= fc::read_input_registers;
  if (!range || !read || reply.size() < 3 || (reply[0] & kExceptionBit) != 0) return reply;
  for (const Key& k : short_) {
    if (!range->covers(k)) continue;
    // A register (or a byte of bits) fewer than asked, and a byte count that says so.
    const std::size_t cut = is_bit_table(range->table) ? 1 : 2;
    reply.resize(reply.size() - std::min(cut, reply.size() - 2));
    reply[1] = static_cast<std::uint8_t>(reply.size() - 2);
    break;
  }
  return reply;
}

std::optional<ModbusSimulator::Key> ModbusSimulator::key_of(std::string_view table,
                                                            std::string_view address) const {
  std::optional<Table> t;
  for (std::size_t i = 0; i < kProfileTableNames.size(); ++i) {
    if (kProfileTableNames[i] == table) t = static_cast<Table>(i);
  }
  const auto a = parse_unsigned(address, 0xFFFF);
  if (!t || !a) return std::nullopt;
  return Key{*t, static_cast<std::uint16_t>(*a)};
}

Bytes ModbusSimulator::handle(ByteView pdu) {
  switch (pdu[0]) {
    case fc::read_coils:
      return read(Table::coil, pdu);
    case fc::read_discrete_inputs:
      return read(Table::discrete, pdu);
    case fc::read_holding_registers:
      return read(Table::holding, pdu);
    case fc::read_input_registers:
      return read(Table::input, pdu);
    case fc::write_single_coil:
    case fc::write_single_register:
    case fc::write_multiple_registers:
      return write(pdu);
    default:
      return exception_pdu(pdu[0], kIllegalFunction);
  }
}

Bytes ModbusSimulator::read(Table table, ByteView pdu) {
  if (pdu.size() != 5) return exception_pdu(pdu[0], kIllegalValue);
  const std::uint16_t start = be16(pdu[1], pdu[2]);
  const std::uint16_t count = be16(pdu[3], pdu[4]);
  if (count == 0 || count > (is_bit_table(table) ? kMaxReadBits : kMaxReadRegisters)) {
    return exception_pdu(pdu[0], kIllegalValue);
  }
  if (!holds(table, start, count)) return exception_pdu(pdu[0], kIllegalAddress);
  Bytes out = {pdu[0]};
  const auto at = [&](std::uint32_t a) {
    const auto it = memory_.find({table, static_cast<std::uint16_t>(a)});
    return it == memory_.end() ? std::uint16_t{0} : it->second;
  };
  if (is_bit_table(table)) {
    out.push_back(static_cast<std::uint8_t>((count + 7) / 8));
    for (std::uint32_t i = 0; i < count; i += 8) {
      std::uint8_t byte = 0;
      for (std::uint32_t b = 0; b < 8 && i + b < count; ++b) {
        if (at(start + i + b) != 0) byte = static_cast<std::uint8_t>(byte | (1u << b));
      }
      out.push_back(byte);
    }
  } else {
    out.push_back(static_cast<std::uint8_t>(2 * count));
    for (std::uint32_t i = 0; i < count; ++i) put_be16(out, at(start + i));
  }
  return out;
}

Bytes ModbusSimulator::write(ByteView pdu) {
  const std::uint8_t fn = pdu[0];
  if (fn == fc::write_single_coil || fn == fc::write_single_register) {
    if (pdu.size() != 5) return exception_pdu(fn, kIllegalValue);
    const std::uint16_t address = be16(pdu[1], pdu[2]);
    const std::uint16_t value = be16(pdu[3], pdu[4]);
    const Table table = fn == fc::write_single_coil ? Table::coil : Table::holding;
    // 6.5: a coil is written ON with 0xFF00, OFF with 0x0000; anything else is illegal.
    if (table == Table::coil && value != 0xFF00 && value != 0x0000) {
      return exception_pdu(fn, kIllegalValue);
    }
    if (!holds(table, address, 1)) return exception_pdu(fn, kIllegalAddress);
    store(table, address, table == Table::coil ? (value != 0 ? 1 : 0) : value);
    return {pdu.begin(), pdu.end()};  // the echo
  }
  // FC 16: address, quantity, byte count, values (6.12).
  if (pdu.size() < 6) return exception_pdu(fn, kIllegalValue);
  const std::uint16_t address = be16(pdu[1], pdu[2]);
  const std::uint16_t count = be16(pdu[3], pdu[4]);
  if (count == 0 || count > kMaxWriteRegisters || pdu[5] != 2 * count ||
      pdu.size() != 6u + 2u * count) {
    return exception_pdu(fn, kIllegalValue);
  }
  if (!holds(Table::holding, address, count)) return exception_pdu(fn, kIllegalAddress);
  for (std::uint16_t i = 0; i < count; ++i) {
    store(Table::holding, static_cast<std::uint16_t>(address + i),
          be16(pdu[6 + 2 * i], pdu[7 + 2 * i]));
  }
  return {pdu.begin(), pdu.begin() + 5};
}

void ModbusSimulator::store(Table table, std::uint16_t address, std::uint16_t word) {
  memory_[{table, address}] = word;
  command(table, address, word);
  drive();
}

// A write of a command's last value to its last point (a control word's register or a coil) is
// that command to the drive: a reset, a stop, a run (not while tripped). A command written as a
// sequence is its last value: the values before it change nothing here unless one is another
// command's (ABB's run 0x047E, 0x047F passes through its stop 0x047E); a sequence over several
// points is that command only while each of its other points holds the last value the sequence
// gave it (direction coil 1 then run coil 1 is run reverse, not run forward). A reset value that
// is also the stop value does both, as on a drive whose reset word has the run bit clear.
void ModbusSimulator::command(Table table, std::uint16_t address, std::uint16_t word) {
  const CommonBindings& c = profile_.common;
  const auto is = [&](const std::optional<ValueBinding>& b) {
    if (!b) return false;
    const ProfilePoint& p = profile_.points[b->point];
    if (p.table != table || p.address != address || b->value != word) return false;
    for (std::size_t i = 0; i < b->points.size(); ++i) {
      const std::size_t other = b->points[i];
      const bool last = std::find(b->points.begin() + static_cast<long>(i) + 1, b->points.end(),
                                  other) == b->points.end();
      if (other == b->point || !last) continue;
      const ProfilePoint& o = profile_.points[other];
      if (memory_[{o.table, o.address}] != b->sequence[i]) return false;
    }
    return true;
  };
  if (is(c.reset_fault)) fault_ = 0;
  if (c.setpoint_runs && c.setpoint_rpm) {
    const ProfilePoint& sp = profile_.points[*c.setpoint_rpm];
    if (sp.table == table && sp.address == address) stopped_ = false;
    if (is(c.stop)) stopped_ = true;
  }
  if (is(c.stop)) {
    running_ = false;
  } else if (is(c.run_forward)) {
    start(false);
  } else if (is(c.run_reverse)) {
    start(true);
  }
}

bool ModbusSimulator::start(bool reverse) {
  if (fault_ != 0) return false;  // a tripped drive does not start until the fault is cleared
  running_ = true;
  reverse_ = reverse;
  return true;
}

std::optional<double> ModbusSimulator::point_value(std::size_t point) const {
  const ProfilePoint& p = profile_.points[point];
  return raw_of(p, words_of(p)) * p.scale;
}

std::vector<std::uint16_t> ModbusSimulator::words_of(const ProfilePoint& p) const {
  std::vector<std::uint16_t> words;
  for (std::uint16_t w = 0; w < p.width(); ++w) {
    words.push_back(memory_.at({p.table, static_cast<std::uint16_t>(p.address + w)}));
  }
  return words;
}

void ModbusSimulator::put(const ProfilePoint& p,
                          const std::optional<std::vector<std::uint16_t>>& words) {
  if (!words) return;
  for (std::uint16_t w = 0; w < p.width(); ++w) {
    auto& word = memory_[{p.table, static_cast<std::uint16_t>(p.address + w)}];
    // A masked point is its bits of the register; the other bits are other points'.
    const std::uint16_t keep = p.mask ? static_cast<std::uint16_t>(~*p.mask) : 0;
    word = static_cast<std::uint16_t>((word & keep) | (*words)[w]);
  }
}

void ModbusSimulator::set_point(std::size_t point, double engineering) {
  const ProfilePoint& p = profile_.points[point];
  put(p, words_for(p, engineering));
}

// The drive behind the registers: the run and fault bits, the fault code, and the actual speed,
// which is the reference while running (in the reverse direction negative) and 0 otherwise.
void ModbusSimulator::drive() {
  const CommonBindings& c = profile_.common;
  // The binding's bits cleared, and bit `nth` of its list set when `on` (the last listed where
  // the list is shorter): running = { any_bit = [0, 1] } shows forward in bit 0, reverse in 1.
  const auto set_bit = [&](const std::optional<BitBinding>& b, bool on, std::size_t nth = 0) {
    if (!b) return;
    const ProfilePoint& p = profile_.points[b->point];
    auto& word = memory_[{p.table, p.address}];
    if (p.type == ValueType::bit) {
      word = on ? 1 : 0;
      return;
    }
    const int shift = p.mask ? std::countr_zero(*p.mask) : 0;
    if (!b->values.empty()) {
      // A state code: the nth listed when on; when off, and the code is this binding's, the
      // first code 0, 1, 2... that is not (another binding of the point keeps its own code).
      const std::uint16_t field = p.mask ? *p.mask : 0xFFFF;
      const auto code = static_cast<std::uint16_t>((word & field) >> shift);
      const auto listed = [&](std::uint16_t v) {
        return std::find(b->values.begin(), b->values.end(), v) != b->values.end();
      };
      std::uint16_t next = code;
      if (on) {
        next = b->values[std::min(nth, b->values.size() - 1)];
      } else if (listed(code)) {
        next = 0;
        while (listed(next)) ++next;
      }
      word = static_cast<std::uint16_t>((word & ~field) | ((next << shift) & field));
      return;
    }
    word = static_cast<std::uint16_t>(word & ~(b->mask() << shift));
    const std::uint8_t bit = b->bits[std::min(nth, b->bits.size() - 1)];
    if (on) word = static_cast<std::uint16_t>(word | 1u << (bit + shift));
  };
  // A drive its set value runs turns while that value is not 0 (setpoint_rpm runs = true), unless
  // its own stop command stopped it since the value was written.
  if (c.setpoint_runs && c.setpoint_rpm) {
    running_ = !stopped_ && point_value(*c.setpoint_rpm).value_or(0) != 0;
    reverse_ = false;
  }
  if (fault_ != 0) running_ = false;  // a trip stops the output
  set_bit(c.running, running_, reverse_ ? 1 : 0);
  set_bit(c.fault, fault_ != 0);
  if (c.fault_code)
    set_point(c.fault_code->point, fault_ * profile_.points[c.fault_code->point].scale);
  if (c.speed_rpm) {
    double speed = 0;
    if (running_ && c.setpoint_rpm) {
      // The same rpm through both points' factors and offsets: the reference's rpm as the
      // speed point's value.
      const double rpm = rpm_scale(c.setpoint_factor, c.setpoint_offset, profile_.options)
                             .rpm(point_value(*c.setpoint_rpm).value_or(0));
      speed = rpm_scale(c.speed_factor, c.speed_offset, profile_.options).value(rpm);
      const ProfilePoint& p = profile_.points[*c.speed_rpm];
      if (p.type != ValueType::f32) speed = std::round(speed / p.scale) * p.scale;
    }
    // An unsigned speed cannot say reverse: it shows the magnitude, as such drives do.
    const ValueType t = profile_.points[*c.speed_rpm].type;
    const bool is_signed = t != ValueType::u16 && t != ValueType::u32;
    set_point(*c.speed_rpm, reverse_ && is_signed ? -speed : speed);
  }
}

std::string ModbusSimulator::state() const {
  std::ostringstream s;
  s << "ok " << profile_.name
    << (running_ ? (reverse_ ? " running reverse" : " running forward") : " stopped") << ", fault "
    << fault_ << (silent_ ? ", silent" : "");
  for (std::size_t i = 0; i < profile_.points.size(); ++i) {
    const ProfilePoint& p = profile_.points[i];
    s << "\n  " << p.name << " = ";
    if (p.type == ValueType::string) {
      s << '"' << text_of(p, words_of(p)) << '"';
    } else {
      s << point_value(i).value_or(0);
    }
  }
  return s.str();
}

std::string ModbusSimulator::control(std::string_view line, TimePoint) {
  const auto w = split_words(line);
  const std::string usage =
      "commands: state | fault N (a native fault code; 0 clears) | run forward|reverse|off | "
      "set POINT VALUE (a string "
      "point: TEXT) | "
      "raw TABLE ADDRESS WORD... | missing TABLE ADDRESS | refuse TABLE ADDRESS CODE [TIMES] | "
      "mute TABLE ADDRESS on|off | short TABLE ADDRESS on|off | silent on|off | late MS | "
      "every-other on|off | reply-code asked|layout | help";
  if (w.empty() || w[0] == "help") return "ok " + usage;
  if (w[0] == "state") return state();
  if (w[0] == "fault" && w.size() == 2) {
    const auto code = parse_unsigned(w[1], 0xFFFF);
    if (!code) return "error: fault takes a number 0..65535";
    fault_ = *code;
    drive();
    return "ok fault " + std::to_string(fault_);
  }
  if (w[0] == "run" && w.size() == 2) {
    // Run or stop as from the drive's own terminals or keypad, not over the line: what a
    // profile without run commands needs to show its running state and speed.
    if (w[1] == "off") {
      running_ = false;
    } else if ((w[1] != "forward" && w[1] != "reverse") || !start(w[1] == "reverse")) {
      return fault_ != 0 ? "error: the drive is faulted (fault 0 clears it)"
                         : "error: run forward|reverse|off";
    }
    drive();
    return "ok run " + w[1];
  }
  if (w[0] == "set" && w.size() >= 3 && profile_.find(w[1]) &&
      profile_.points[*profile_.find(w[1])].type == ValueType::string) {
    // The text is the rest of the line, spaces and all.
    const ProfilePoint& p = profile_.points[*profile_.find(w[1])];
    std::string_view text = line.substr(line.find(w[1], line.find("set") + 3) + w[1].size());
    while (!text.empty() && text.front() == ' ') text.remove_prefix(1);
    const auto words = words_for_text(p, text);
    if (!words) {
      return "error: " + w[1] + " takes at most " + std::to_string(2 * p.width()) +
             " printable ASCII characters";
    }
    put(p, words);
    return "ok " + w[1] + " = \"" + std::string(text) + "\"";
  }
  if (w[0] == "set" && w.size() == 3) {
    const auto point = profile_.find(w[1]);
    if (!point) return "error: no point " + w[1];
    char* end = nullptr;
    const double v = std::strtod(w[2].c_str(), &end);
    if (end == w[2].c_str() || *end != '\0' || !words_for(profile_.points[*point], v)) {
      return "error: " + w[2] + " is not a value of " + w[1];
    }
    set_point(*point, v);
    return "ok " + w[1] + " = " + w[2];
  }
  if (w[0] == "missing" && w.size() == 3) {
    const auto key = key_of(w[1], w[2]);
    if (!key) return "error: missing TABLE ADDRESS (holding 202, input 7, ...)";
    missing_.insert(*key);
    return "ok " + w[1] + " " + w[2] + " answers illegal data address from now on";
  }
  if (w[0] == "refuse" && (w.size() == 4 || w.size() == 5)) {
    const auto key = key_of(w[1], w[2]);
    const auto code = parse_unsigned(w[3], 0xFF);
    const auto times = w.size() == 5 ? parse_unsigned(w[4]) : std::optional<std::uint32_t>(1);
    if (!key || !code || *code == 0 || !times || *times == 0) {
      return "error: refuse TABLE ADDRESS CODE [TIMES] (holding 100 6: busy, once)";
    }
    refused_[*key] = {static_cast<std::uint8_t>(*code), *times};
    return "ok the next " + std::to_string(*times) + " requests covering " + w[1] + " " + w[2] +
           " answer exception " + w[3];
  }
  if ((w[0] == "mute" || w[0] == "short") && w.size() == 4) {
    const auto key = key_of(w[1], w[2]);
    const auto on = parse_on_off(w[3]);
    if (!key || !on) return "error: " + w[0] + " TABLE ADDRESS on|off";
    std::set<Key>& keys = w[0] == "mute" ? mute_ : short_;
    if (*on) {
      keys.insert(*key);
    } else {
      keys.erase(*key);
    }
    return "ok " + w[0] + " " + w[1] + " " + w[2] + " " + w[3];
  }
  if (w[0] == "raw" && w.size() >= 4) {
    const auto key = key_of(w[1], w[2]);
    if (!key) return "error: raw TABLE ADDRESS WORD... (input 200 0x7FC0 0x0000)";
    std::vector<std::uint16_t> words;
    for (std::size_t i = 3; i < w.size(); ++i) {
      const auto word = parse_unsigned(w[i], 0xFFFF);
      if (!word) return "error: " + w[i] + " is not a register value 0..65535";
      words.push_back(static_cast<std::uint16_t>(*word));
    }
    for (std::size_t i = 0; i < words.size(); ++i) {
      memory_[{key->first, static_cast<std::uint16_t>(key->second + i)}] = words[i];
    }
    return "ok " + std::to_string(words.size()) + " registers from " + w[1] + " " + w[2];
  }
  if (w[0] == "late" && w.size() == 2) {
    const auto ms = parse_unsigned(w[1], 60000);
    if (!ms) return "error: late MS, 0..60000";
    late_ = Millis(*ms);
    return "ok answers " + w[1] + " ms late";
  }
  if (w[0] == "every-other" && w.size() == 2 && parse_on_off(w[1])) {
    every_other_ = *parse_on_off(w[1]);
    heard_ = 0;
    return "ok every-other " + w[1];
  }
  if (w[0] == "reply-code" && w.size() == 2 && (w[1] == "asked" || w[1] == "layout")) {
    reply_as_layout_ = w[1] == "layout";
    return "ok own write codes answered under " +
           std::string(reply_as_layout_ ? "the code they are laid out as" : "the code asked");
  }
  if (w[0] == "silent" && w.size() == 2 && parse_on_off(w[1])) {
    silent_ = *parse_on_off(w[1]);
    return "ok silent " + w[1];
  }
  return "error: unknown command '" + std::string(line) + "'; " + usage;
}

}  // namespace drivegate::modbus_device
