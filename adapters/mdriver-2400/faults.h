// The driver's error codes (vendor document, "モータドライバ エラーコード"), the unified faults
// they stand for, and their labels.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "drivegate/common.h"
#include "drivegate/point.h"

namespace drivegate::mdriver {

struct ErrorCodeInfo {
  std::uint8_t code;
  std::string_view name;         // simulator `fault <name>` and point labels
  std::string_view description;  // the document's row, in English
  Fault fault;
};

// Rows 0x01..0x0E of the error table (0x00 = no error).
std::span<const ErrorCodeInfo> error_codes();
std::optional<ErrorCodeInfo> find_error(std::uint8_t code);
std::optional<ErrorCodeInfo> find_error(std::string_view name);
// Unified fault of a native code; 0x0A (reserved) and codes past the table map to Fault::other.
Fault fault_of(std::uint8_t code);
// Labels of the error_code point: "none" for 0x00, then the table's names by code.
std::vector<Label> error_code_labels();

// Error table, 0x0C (通信エラー) and its note (*): the driver stops with this error after 6 s
// without a frame from the master.
inline constexpr std::uint8_t kCommErrorCode = 0x0C;
inline constexpr std::chrono::milliseconds kSilenceTrip{6000};

// native_fault for the fixed-code error (section 3 No.1, R4..R7 = 00 00 00 00): not an error code
// of the table, so a value outside its 8-bit range.
inline constexpr std::uint32_t kNativeFixedCodeError = 0x100;

}  // namespace drivegate::mdriver
