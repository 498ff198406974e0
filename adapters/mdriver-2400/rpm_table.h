// Frequency code <-> compressor rpm, by the document's conversion table, not by a formula: the
// table is 18 rpm a step except 0x1F = 557, 0x20 = 573 and 0x60 = 1722.
#pragma once

#include <array>
#include <cstdint>
#include <optional>

namespace drivegate::mdriver {

inline constexpr std::size_t kRpmTableSize = 0xA0;  // codes 0x00..0x9F

// Vendor document, 通信仕様, 【参考】コンプレッサ回転数とHEXコード変換表 <通常運転モード>,
// column 回転数 rpm, transcribed row by row (identical in the <連続運転モード> table).
inline constexpr std::array<std::uint16_t, kRpmTableSize> kRpmTable = {
    0,    18,   36,   54,   72,   90,   108,  126,   // 0x00..0x07
    144,  162,  180,  198,  216,  234,  252,  270,   // 0x08..0x0F
    288,  306,  324,  342,  360,  378,  396,  414,   // 0x10..0x17
    432,  450,  468,  486,  504,  522,  540,  557,   // 0x18..0x1F
    573,  591,  609,  627,  645,  663,  681,  699,   // 0x20..0x27
    717,  735,  753,  771,  789,  807,  825,  843,   // 0x28..0x2F
    861,  879,  897,  915,  933,  951,  969,  987,   // 0x30..0x37
    1005, 1023, 1041, 1059, 1077, 1095, 1113, 1131,  // 0x38..0x3F
    1149, 1167, 1185, 1203, 1221, 1239, 1257, 1275,  // 0x40..0x47
    1293, 1311, 1329, 1347, 1365, 1383, 1401, 1419,  // 0x48..0x4F
    1437, 1455, 1473, 1491, 1509, 1527, 1545, 1563,  // 0x50..0x57
    1581, 1599, 1617, 1635, 1653, 1671, 1689, 1707,  // 0x58..0x5F
    1722, 1740, 1758, 1776, 1794, 1812, 1830, 1848,  // 0x60..0x67
    1866, 1884, 1902, 1920, 1938, 1956, 1974, 1992,  // 0x68..0x6F
    2010, 2028, 2046, 2064, 2082, 2100, 2118, 2136,  // 0x70..0x77
    2154, 2172, 2190, 2208, 2226, 2244, 2262, 2280,  // 0x78..0x7F
    2298, 2316, 2334, 2352, 2370, 2388, 2406, 2424,  // 0x80..0x87
    2442, 2460, 2478, 2496, 2514, 2532, 2550, 2568,  // 0x88..0x8F
    2586, 2604, 2622, 2640, 2658, 2676, 2694, 2712,  // 0x90..0x97
    2730, 2748, 2766, 2784, 2802, 2820, 2838, 2856,  // 0x98..0x9F
};

// Section 3 No.2: lowest running speed 504 rpm = 0x1C; the README's reading: 0x1F = 557, 0x20 =
// 573.
static_assert(kRpmTable[0x1C] == 504 && kRpmTable[0x1F] == 557 && kRpmTable[0x20] == 573);

// rpm of a code; codes past the table extrapolate at 18 rpm a step (0.3 rps, section 3 No.2).
std::int32_t rpm_of_code(std::uint8_t code);
// Nearest running code (0x1C..0x9F) for `rpm`; ties take the lower code. nullopt under 504 rpm
// (lowest running speed, section 3 No.2) or above 2856 rpm (end of the table).
std::optional<std::uint8_t> code_for_rpm(std::int32_t rpm);

}  // namespace drivegate::mdriver
