// A description checked by hand, without a line: bytes decoded into named fields, a message
// encoded from field values (`drivegate protocol decode|encode`, docs/protocols.md), and the
// description as the data of the Wireshark dissector (`drivegate protocol dissector`,
// adapters/framed/dissector.lua). Pure.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "description.h"
#include "drivegate/bytes.h"
#include "drivegate/options.h"

namespace drivegate::framed {

// "A5 05 0x00 3" -> bytes: hex pairs, blanks and 0x prefixes allowed; nullopt for anything else.
std::optional<Bytes> parse_hex(const std::string& text);
std::string hex_text(ByteView bytes);

// Every frame in `bytes`, in order, one block of lines each: the message, its direction, its
// bytes, then each field and check; bytes that make no frame said as such. `dir`: only that
// direction; nullopt: a request where one fits, else a reply.
std::string decode_text(const Description& d, ByteView bytes, std::optional<Direction> dir);

// The message's bytes: each field the value given, else what the description sends (its values
// expression, the variable of its name) with the options given over their defaults. nullopt and
// `error` for a message or field that is not there.
std::optional<Bytes> encode_message(const Description& d, const std::string& message,
                                    const std::vector<std::pair<std::string, double>>& fields,
                                    const Options& options, std::string& error);

// The description as the data adapters/framed/dissector.lua decodes it with: a Lua chunk holding
// its messages' layouts (names, offsets, widths, encodings), constants and checks with their
// parameters, which hands itself to the dissector when loaded (before it or after).
std::string lua_table(const Description& d);

}  // namespace drivegate::framed
