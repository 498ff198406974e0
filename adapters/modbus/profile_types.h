// The keys of a profile's [[point]] that depend on its type (docs/profiles.md, "[[point]]"):
// `registers` of a string, `byte_order` (or its shorthand `word_order`) of a 32-bit, 64-bit or
// string value, the labels `bits` and `values`, and a string's being read-only. Part of
// parse_profile(); each error names the file and line through the Diagnostics.
#pragma once

#include "drivegate/toml_reader.h"
#include "profile.h"

namespace drivegate::modbus_device {

// `registers` (required of a string point, refused elsewhere): false after an error. Read before
// the point's width is used.
bool read_registers(TableReader& r, ProfilePoint& p, Diagnostics& diag);

// `byte_order` or `word_order`: false after an error.
bool read_byte_order(TableReader& r, ProfilePoint& p, Diagnostics& diag);

// `bits = { N = "name" }` or `values = { N = "name" }`, after the point's scale: false after an
// error.
bool read_labels(TableReader& r, ProfilePoint& p, Diagnostics& diag);

// A string point is read-only: access, min and max say nothing else. False after an error.
bool check_read_only(TableReader& r, ProfilePoint& p, Diagnostics& diag);

}  // namespace drivegate::modbus_device
