#include "profile_examples.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "codec.h"
#include "drivegate/crc.h"
#include "planner.h"
#include "values.h"

namespace drivegate::modbus_device {
namespace {

std::optional<Bytes> parse_hex(const std::string& text) {
  std::string digits;
  for (const char c : text) {
    if (c == ' ') continue;
    if (!std::isxdigit(static_cast<unsigned char>(c))) return std::nullopt;
    digits += c;
  }
  if (digits.empty() || digits.size() % 2 != 0) return std::nullopt;
  Bytes out;
  for (std::size_t i = 0; i < digits.size(); i += 2) {
    out.push_back(static_cast<std::uint8_t>(std::stoul(digits.substr(i, 2), nullptr, 16)));
  }
  return out;
}

std::string hex_text(ByteView bytes) {
  std::string out;
  char b[4];
  for (const std::uint8_t c : bytes) {
    std::snprintf(b, sizeof b, "%s%02X", out.empty() ? "" : " ", c);
    out += b;
  }
  return out;
}

std::string number_text(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.10g", v);
  return b;
}

// The table a read function reads: the one read_function() reads with it.
std::optional<Table> table_read_by(std::uint8_t function) {
  for (const Table t : {Table::coil, Table::discrete, Table::input, Table::holding}) {
    if (read_function(t) == function) return t;
  }
  return std::nullopt;
}

// The same number, allowing for the binary fractions of a scale (14.95 is 1495 x 0.01).
bool same_value(double a, double b) {
  return std::fabs(a - b) <= 1e-9 * std::max(1.0, std::fabs(b));
}

// Why an RTU example's bytes are no frame: a CRC that does not hold gives the one that would (a
// manual's misprint is most often its CRC's two bytes swapped); one that holds means the bytes
// are not as long as the function's layout and counts (Application Protocol 6.x) make its frame.
std::string why_not_a_frame(Framing framing, const Bytes& frame, bool request) {
  if (framing != Framing::rtu || frame.size() < 4) return {};
  const ByteView body(frame.data(), frame.size() - 2);
  const std::uint16_t crc = crc16_modbus(body);
  const Bytes wanted{static_cast<std::uint8_t>(crc & 0xFF), static_cast<std::uint8_t>(crc >> 8)};
  if (!std::equal(wanted.begin(), wanted.end(), frame.end() - 2)) {
    return " (the CRC of its bytes is " + hex_text(wanted) + ")";
  }
  const std::string function = "function " + hex_text(Bytes{frame[1]});
  if (request) {
    const RequestLength length = request_length(ByteView(frame.data() + 1, frame.size() - 3));
    if (length.status == RequestLength::Status::known) {
      // The address, the PDU, the CRC.
      return ": its CRC holds, but a " + function + " request of these counts is " +
             std::to_string(length.size + 3) + " bytes, not " + std::to_string(frame.size());
    }
  }
  return ": its CRC holds, but not where the layout and counts of " + function + " end its " +
         (request ? "request" : "reply");
}

// One frame, decoded whole: `what` says which ("request", "reply").
std::optional<Adu> decode_whole(const Profile& profile, const std::string& text, bool request,
                                std::vector<std::string>& out) {
  const char* what = request ? "request" : "reply";
  const auto frame = example_frame(profile, text);
  if (!frame) {
    out.push_back(std::string(what) + " is not a frame's bytes in hex");
    return std::nullopt;
  }
  const std::vector<CodeLayout> layouts = write_layouts(profile);
  const auto d = request ? decode_request(profile.line.framing, *frame, layouts)
                         : decode_reply(profile.line.framing, *frame, layouts);
  if (d.status != DecodeStatus::frame) {
    out.push_back(std::string(what) + " " + hex_text(*frame) + " is not a good frame" +
                  why_not_a_frame(profile.line.framing, *frame, request));
    return std::nullopt;
  }
  if (d.consumed != frame->size()) {
    out.push_back(std::string(what) + " has " + std::to_string(frame->size() - d.consumed) +
                  " bytes after its frame");
    return std::nullopt;
  }
  return d.frame;
}

void check_read(const Profile& profile, const ProfileExample& e, const Adu& request,
                std::vector<std::string>& out) {
  const std::uint8_t fn = request.pdu[0];
  const Table table = *table_read_by(fn);
  if (request.pdu.size() != 5) {
    out.emplace_back("the request is not a read of a start and a quantity");
    return;
  }
  const std::uint16_t start = be16(request.pdu[1], request.pdu[2]);
  const std::uint16_t count = be16(request.pdu[3], request.pdu[4]);
  std::optional<Adu> reply;
  if (e.reply.empty()) {
    out.emplace_back("a read needs its reply");
  } else {
    reply = decode_whole(profile, e.reply, false, out);
  }
  const std::size_t data =
      is_bit_table(table) ? (std::size_t{count} + 7) / 8 : 2 * std::size_t{count};
  if (reply) {
    if (reply->address != request.address) {
      out.push_back("the reply comes from address " + std::to_string(reply->address) +
                    ", the request asks " + std::to_string(request.address));
      reply.reset();
    } else if (reply->pdu[0] != fn || reply->pdu.size() != 2 + data || reply->pdu[1] != data) {
      out.push_back("the reply is not " + std::to_string(data) + " bytes of data for function " +
                    hex_text(Bytes{fn}));
      reply.reset();
    }
  }
  for (const auto& [name, want] : e.expect) {
    const auto index = profile.find(name);
    if (!index) continue;  // reported when the example was read
    const ProfilePoint& p = profile.points[*index];
    if (p.table != table || p.address < start || p.address + p.width() > start + count) {
      out.push_back("'" + name + "' (" +
                    std::string(kProfileTableNames[static_cast<std::size_t>(p.table)]) + " " +
                    std::to_string(p.address) + ") is not in the request's range");
      continue;
    }
    if (!reply) continue;
    const std::size_t offset = p.address - start;
    std::vector<std::uint16_t> words;
    if (is_bit_table(table)) {
      words.push_back(static_cast<std::uint16_t>((reply->pdu[2 + offset / 8] >> (offset % 8)) & 1));
    } else {
      for (std::size_t w = 0; w < p.width(); ++w) {
        words.push_back(be16(reply->pdu[2 + 2 * (offset + w)], reply->pdu[3 + 2 * (offset + w)]));
      }
    }
    const double got = raw_of(p, words) * p.scale;
    if (!same_value(got, want)) {
      out.push_back("'" + name + "' reads " + number_text(got) + " from the reply, not " +
                    number_text(want));
    }
  }
}

// `fn` is the protocol's code the request is laid out as: its own, or the one a point's own
// write code (write_code) is laid out as.
void check_write(const Profile& profile, const ProfileExample& e, const Adu& request,
                 std::uint8_t fn, std::vector<std::string>& out) {
  const ByteView pdu = request.pdu;
  const Table table = fn == fc::write_single_coil ? Table::coil : Table::holding;
  std::uint16_t start = 0;
  std::vector<std::uint16_t> words;  // what the request writes, register by register
  if (fn == fc::write_multiple_registers) {
    if (pdu.size() < 6 || pdu.size() != 6u + pdu[5] || pdu[5] != 2 * be16(pdu[3], pdu[4])) {
      out.emplace_back("the request's counts disagree");
      return;
    }
    start = be16(pdu[1], pdu[2]);
    for (std::size_t i = 6; i + 1 < pdu.size(); i += 2) words.push_back(be16(pdu[i], pdu[i + 1]));
  } else {
    if (pdu.size() != 5) {
      out.emplace_back("the request is not an address and a value");
      return;
    }
    start = be16(pdu[1], pdu[2]);
    std::uint16_t v = be16(pdu[3], pdu[4]);
    // FC 05: ON is FF00, OFF 0000 (Application Protocol 6.5).
    if (fn == fc::write_single_coil) {
      if (v != 0xFF00 && v != 0) {
        out.emplace_back("a coil is written FF00 or 0000");
        return;
      }
      v = v != 0 ? 1 : 0;
    }
    words.push_back(v);
  }
  std::vector<bool> covered(words.size(), false);
  for (const auto& [name, want] : e.expect) {
    const auto index = profile.find(name);
    if (!index) continue;
    const ProfilePoint& p = profile.points[*index];
    if (p.table != table || p.address < start || p.address + p.width() > start + words.size()) {
      out.push_back("'" + name + "' is not in the registers the request writes");
      continue;
    }
    // A device's own code writes the points that name it (the protocol's codes may write those
    // too: a manual's frames that save).
    if (request.pdu[0] != fn && p.write_code != request.pdu[0]) {
      const std::string code = "0x" + hex_text(Bytes{request.pdu[0]});
      out.push_back("'" + name + "' is not written with " + code +
                    " (its point has no write_code = " + code + ")");
    }
    const auto mine = words_for(p, want);
    if (!mine) {
      out.push_back("'" + name + "' cannot carry " + number_text(want));
      continue;
    }
    const std::size_t offset = p.address - start;
    for (std::size_t w = 0; w < mine->size(); ++w) {
      covered[offset + w] = true;
      if ((*mine)[w] != words[offset + w]) {
        char b[64];
        std::snprintf(b, sizeof b, "%04X where the request has %04X", (*mine)[w],
                      words[offset + w]);
        out.push_back("'" + name + "' = " + number_text(want) + " writes " + b);
        break;
      }
    }
  }
  for (std::size_t i = 0; i < covered.size(); ++i) {
    if (!covered[i]) {
      out.push_back("the request writes address " + std::to_string(start + i) +
                    ", which no point of expect covers");
    }
  }
  if (e.reply.empty()) return;
  const auto reply = decode_whole(profile, e.reply, false, out);
  if (!reply) return;
  // FC 05 and 06 echo the request, FC 16 its address and quantity (6.5, 6.6, 6.12); a write
  // code's echo is under that code or the one it is laid out as.
  const std::size_t echo = 5;
  if (reply->address != request.address || reply->pdu.size() != echo ||
      (reply->pdu[0] != request.pdu[0] && reply->pdu[0] != fn) ||
      !std::equal(reply->pdu.begin() + 1, reply->pdu.end(), request.pdu.begin() + 1)) {
    out.emplace_back("the reply is not the slave's echo of the request");
  }
}

}  // namespace

void read_profile_examples(const toml::table& root, TableReader& top, Diagnostics& diag,
                           Profile& profile) {
  top.node("example");
  if (root.get("example") == nullptr) return;
  const toml::array* examples = array_of_tables(root, "example", diag);
  if (examples == nullptr) return;
  for (const toml::node& n : *examples) {
    const toml::table& t = *n.as_table();
    TableReader r(t, "example", diag);
    r.expect({"request", "reply", "expect", "note"});
    ProfileExample e;
    e.line = static_cast<std::uint32_t>(line_of(t));
    e.request = r.string("request", true).value_or("");
    e.reply = r.string("reply", false).value_or("");
    e.note = r.string("note", false).value_or("");
    bool ok = true;
    for (const auto& [key, text] : {std::pair{"request", &e.request}, {"reply", &e.reply}}) {
      if (!text->empty() && !example_frame(profile, *text)) {
        diag.error(r.node(key), std::string("example.") + key,
                   profile.line.framing == Framing::rtu
                       ? "must be the frame's bytes in hex, such as \"01 04 08 38 00 01 B3 A6\""
                       : "must be the ASCII frame as printed, such as \":010300000001FB\"");
        ok = false;
      }
    }
    const toml::table* expect = r.table("expect", true);
    if (expect != nullptr) {
      for (const auto& [k, v] : *expect) {
        const std::string name(k.str());
        std::optional<double> value;
        if (const auto* i = v.as_integer()) value = static_cast<double>(i->get());
        if (const auto* f = v.as_floating_point()) value = f->get();
        if (!profile.find(name)) {
          diag.error(&v, "example.expect." + name, "no point is called '" + name + "'");
          ok = false;
        } else if (!value || !std::isfinite(*value)) {
          diag.error(&v, "example.expect." + name, "must be a number (the engineering value)");
          ok = false;
        } else {
          e.expect.emplace_back(name, *value);
        }
      }
    }
    if (ok && expect != nullptr) profile.examples.push_back(std::move(e));
  }
}

std::optional<Bytes> example_frame(const Profile& profile, const std::string& text) {
  if (profile.line.framing == Framing::rtu) return parse_hex(text);
  if (text.empty() || text[0] != ':') return std::nullopt;
  Bytes out(text.begin(), text.end());
  if (!text.ends_with("\r\n")) {
    out.push_back('\r');
    out.push_back('\n');
  }
  return out;
}

std::vector<std::string> check_example(const Profile& profile, const ProfileExample& example) {
  std::vector<std::string> out;
  const auto request = decode_whole(profile, example.request, true, out);
  if (!request) return out;
  std::uint8_t fn = request->pdu[0];
  for (const CodeLayout& l : write_layouts(profile)) {
    if (l.code == fn) fn = l.like;
  }
  if (table_read_by(fn)) {
    check_read(profile, example, *request, out);
  } else if (fn == fc::write_single_coil || fn == fc::write_single_register ||
             fn == fc::write_multiple_registers) {
    check_write(profile, example, *request, fn, out);
  } else {
    out.push_back("function " + hex_text(Bytes{fn}) +
                  " is not a read (01 - 04) or a write (05, 06, 10) a profile describes");
  }
  return out;
}

std::vector<std::string> check_examples(const Profile& profile, const std::string& source) {
  std::vector<std::string> out;
  for (const ProfileExample& e : profile.examples) {
    for (const std::string& why : check_example(profile, e)) {
      std::string line = source;
      line += ":" + std::to_string(e.line) + ": example: ";
      line += why;
      out.push_back(std::move(line));
    }
  }
  return out;
}

}  // namespace drivegate::modbus_device
