// [[example]]: the manual's frames in a profile, held against the profile by check_example()
// (profile_examples.h), the function `drivegate profile check` and the library test run: a read's
// reply decodes to the values expected, a write of the values expected is the request's data,
// every CRC is good, and a frame the profile cannot agree with says why.
#include "profile_examples.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "profile.h"
#include "profile_check.h"
#include "profile_support.h"

namespace drivegate::modbus_device {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::IsEmpty;

// Eaton M-Max's input registers 2104 - 2105 and control word 2000 (MN04020003E p.138, p.137),
// and the p.140 / p.141 frames at slave 5.
constexpr const char* kBase = R"toml(
[profile]
name = "ex"
source = "a test"
[line]
baud = 9600
parity = "none"
stop_bits = 2
[[point]]
name = "control_word"
table = "holding"
address = 2000   # p.137
type = "u16"
[[point]]
name = "speed_setpoint"
table = "holding"
address = 2002   # p.137
type = "u16"
scale = 0.01
[[point]]
name = "motor_speed"
table = "input"
address = 2104   # p.138
type = "s16"
[[point]]
name = "motor_current"
table = "input"
address = 2105   # p.138
type = "u16"
scale = 0.01
)toml";

std::vector<std::string> check(const std::string& examples) {
  auto r = parse_profile(std::string(kBase) + examples, "ex.toml");
  if (auto* e = std::get_if<std::vector<std::string>>(&r)) return *e;
  return check_examples(std::get<Profile>(r), "ex.toml");
}

TEST(ProfileExamples, TheManualsReadAndWriteAgreeWithTheProfile) {
  EXPECT_THAT(check(R"toml(
[[example]]
request = "05 04 08 38 00 02 F3 E2"
reply = "05 04 04 05 D7 00 18 0E BA"
expect = { motor_speed = 1495, motor_current = 0.24 }
[[example]]
request = "0506 07D0 0003 C8C2"
expect = { control_word = 3 }
)toml"),
              IsEmpty());
}

TEST(ProfileExamples, AValueTheReplyDoesNotCarryIsAnErrorOnTheExamplesLine) {
  EXPECT_THAT(
      check(R"toml(
[[example]]
request = "05 04 08 38 00 02 F3 E2"
reply = "05 04 04 05 D7 00 18 0E BA"
expect = { motor_speed = 1496 }
)toml"),
      ElementsAre("ex.toml:32: example: 'motor_speed' reads 1495 from the reply, not 1496"));
}

TEST(ProfileExamples, ABadCrcIsAnErrorThatGivesTheRightOne) {
  // The manual prints the FC 06 request's CRC swapped (C2 C8): corrected in the file, with a note.
  support::expect_refused(
      check,
      {{R"toml(
[[example]]
request = "05 06 07 D0 00 03 C2 C8"
expect = { control_word = 3 }
)toml",
        {"request 05 06 07 D0 00 03 C2 C8 is not a good frame (the CRC of its bytes is C8 C2)"}},
       {R"toml(
[[example]]
request = "05 04 08 38 00 02 F3 E2"
reply = "05 04 04 05 D7 00 18 0E BB"
expect = { motor_speed = 1495 }
)toml",
        {"reply 05 04 04 05 D7 00 18 0E BB is not a good frame"}}});
}

// A frame whose CRC holds over bytes of the wrong length (a byte left out, or one too many, and
// its CRC recomputed): the length is what is wrong, and the error says so, not the CRC.
TEST(ProfileExamples, AGoodCrcOverTheWrongLengthIsCalledAWrongLength) {
  // CRC-16/MODBUS of the bytes before it (Modbus over Serial Line 6.2.2).
  const std::string long_write = "05 06 07 D0 00 03 00 C3 96";
  const std::string short_reply = "05 04 04 05 D7 00 BF 4F";
  support::expect_refused(
      check, {{"[[example]]\nrequest = \"" + long_write + "\"\nexpect = { control_word = 3 }\n",
               {"request " + long_write +
                " is not a good frame: its CRC holds, but a function 06 request of these counts "
                "is 8 bytes, not 9"}},
              {"[[example]]\nrequest = \"05 04 08 38 00 02 F3 E2\"\nreply = \"" + short_reply +
                   "\"\nexpect = { motor_speed = 1495 }\n",
               {"reply " + short_reply +
                " is not a good frame: its CRC holds, but not where the layout and counts of "
                "function 04 end its reply"}}});
}

TEST(ProfileExamples, AWriteMustBeTheRequestsDataWhole) {
  // FC 10 of 2000 - 2002: 2001 is no point of this profile.
  support::expect_refused(check, {{R"toml(
[[example]]
request = "05 10 07 D0 00 03 06 00 01 00 00 27 10 D1 25"
reply = "05 10 07 D0 00 03 81 01"
expect = { control_word = 1, speed_setpoint = 100 }
)toml",
                                   {"writes address 2001, which no point of expect covers"}},
                                  {R"toml(
[[example]]
request = "05 06 07 D0 00 03 C8 C2"
expect = { control_word = 4 }
)toml",
                                   {"'control_word' = 4 writes 0004 where the request has 0003"}}});
}

TEST(ProfileExamples, PointsOutsideTheRequestAndBadTextAreErrors) {
  EXPECT_THAT(
      check(R"toml(
[[example]]
request = "05 03 08 38 00 02 46 22"
reply = "05 03 04 05 D7 00 18 00 00"
expect = { motor_speed = 1495 }
)toml"),
      testing::Contains(HasSubstr("'motor_speed' (input 2104) is not in the request's range")));
  support::expect_refused(check, {{R"toml(
[[example]]
request = "05 04 zz"
expect = { nothing = 1 }
)toml",
                                   {"example.request: must be the frame's bytes in hex",
                                    "example.expect.nothing: no point is called 'nothing'"}},
                                  {R"toml(
[[example]]
request = "05 04 08 38 00 02 F3 E2"
expect = { motor_speed = 1495 }
)toml",
                                   {"a read needs its reply"}},
                                  // A frame inside the frame: bytes after the request's end.
                                  {R"toml(
[[example]]
request = "05 06 07 D0 00 03 C8 C2 05 06 07 D0 00 03 C8 C2"
expect = { control_word = 3 }
)toml",
                                   {"bytes after its frame"}}});
}

TEST(ProfileCheck, WarnsOfAnUnboundCommonBlockAndAnUncitedAddress) {
  const std::string text = std::string(kBase) +
                           "[[point]]\nname = \"extra\"\ntable = \"holding\"\naddress = 9\n"
                           "type = \"u16\"\n";
  const ProfileReport r = check_profile(text, "ex.toml");
  EXPECT_THAT(r.errors, IsEmpty());
  EXPECT_THAT(r.warnings,
              ElementsAre(HasSubstr("not bound: speed_rpm, setpoint_rpm, running, fault, "
                                    "fault_code, stop, run_forward"),
                          HasSubstr("ex.toml:31: point: 'extra' cites no source")));
  // An overlap is a parse error, reported as one.
  const ProfileReport o = check_profile(
      std::string(kBase) +
          "[[point]]\nname = \"wide\"\ntable = \"input\"\naddress = 2103 # x\ntype = \"u32\"\n",
      "ex.toml");
  EXPECT_THAT(o.errors, ElementsAre(HasSubstr("'wide' overlaps 'motor_speed'")));
}

}  // namespace
}  // namespace drivegate::modbus_device
