// The driver's error codes (section "モータドライバ エラーコード") and their unified faults.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include "drivegate/common.h"

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

// native_fault for the fixed-code error (R4..R7 = 00 00 00 00): not an error code of the table,
// so a value outside its 8-bit range.
inline constexpr std::uint32_t kNativeFixedCodeError = 0x100;

}  // namespace drivegate::mdriver
