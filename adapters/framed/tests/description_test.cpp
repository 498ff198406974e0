// Reading descriptions (description_parser.h): every shipped one is valid; every mistake is
// "FILE:LINE: key: what", all of them in one pass; and the safety rules hold at load: a
// description that can send a motion command with no confirming rule or no limits is refused.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "description_parser.h"
#include "settings.h"

namespace drivegate::framed {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

std::vector<std::string> errors_of(const std::string& text) {
  auto r = parse_description(text, "t.toml");
  if (const auto* e = std::get_if<std::vector<std::string>>(&r)) return *e;
  return {};
}

std::shared_ptr<const Description> parsed(const std::string& text) {
  auto r = parse_description(text, "t.toml");
  if (const auto* e = std::get_if<std::vector<std::string>>(&r)) {
    for (const auto& line : *e) ADD_FAILURE() << line;
    return nullptr;
  }
  return std::get<std::shared_ptr<const Description>>(r);
}

// A small request / reply protocol that can run a motor, valid as it stands.
const std::string kHead = R"([protocol]
name = "tiny"
summary = "a drive"
document = "the manual"

[line]
baud = 9600

[check.sum]
kind = "sum"

[[message]]
name = "run"
direction = "request"
layout = "01 speed:u16 cs:sum"
values = { speed = "setpoint" }
replies = ["ack"]

[[message]]
name = "halt"
direction = "request"
layout = "02 00 00 cs:sum"
replies = ["ack"]

[[message]]
name = "ack"
direction = "reply"
layout = "06 status:u8 cs:sum"
)";

const std::string kRules = R"(
[[command.run_forward]]
send = "run"
accept = "status == 0"

[[command.stop]]
send = "halt"

[setpoint]
min = 100
max = 3000
)";

TEST(Descriptions, EveryShippedOneIsValid) {
  ASSERT_FALSE(shipped_names().empty());
  for (const auto name : shipped_names()) {
    auto r = parse_description(*shipped_text(name), std::string(name) + ".toml");
    if (const auto* e = std::get_if<std::vector<std::string>>(&r)) {
      for (const auto& line : *e) ADD_FAILURE() << line;
      continue;
    }
    EXPECT_EQ(std::get<std::shared_ptr<const Description>>(r)->name, name);
  }
}

TEST(Descriptions, AValidOneReadsAsWritten) {
  const auto d = parsed(kHead + kRules);
  ASSERT_NE(d, nullptr);
  EXPECT_EQ(d->line.baud, 9600u);
  EXPECT_EQ(d->line.parity, Parity::none);
  ASSERT_EQ(d->messages.size(), 3u);
  EXPECT_EQ(d->messages[0].size, 4u);
  EXPECT_EQ(d->messages[0].replies, (std::vector<std::size_t>{2}));
  EXPECT_EQ(d->commands.at(Command::run_forward).size(), 1u);
  EXPECT_TRUE(d->setpoint->limited);
}

TEST(Descriptions, EveryErrorNamesFileLineAndKeyAllInOnePass) {
  const auto e = errors_of(kHead + R"(
[[point]]
name = "temperature"
table = "input"
type = "u17"
description = "x"

[[message]]
name = "bad"
direction = "sideways"
layout = "07 speed:u9 ZZ"

[[command.run_forward]]
send = "run"
accept = "status == 0 &&"

[[command.jump]]
send = "run"
)" + "\n[setpoint]\nmin = 100\nmax = 3000\n[[command.stop]]\nsend = \"halt\"\n");
  EXPECT_THAT(
      e, ElementsAre(HasSubstr("t.toml:33: point.type: must be one of u16, i16, u32, i32, f32, "
                               "string (got 'u17')"),
                     HasSubstr("t.toml:38: message.direction: must be one of request, reply "
                               "(got 'sideways')"),
                     HasSubstr("t.toml:39: message.bad.layout: token 2 'speed:u9': unknown type"),
                     HasSubstr("t.toml:43: command.run_forward.accept: expression ends too early"),
                     HasSubstr("t.toml:45: command.jump: no command 'jump'")));
}

TEST(Descriptions, AMotionCommandWithoutAConfirmingRuleIsRefused) {
  std::string text = kHead + kRules;
  text.replace(text.find("accept = \"status == 0\"\n"), 23, "");
  EXPECT_THAT(errors_of(text),
              ElementsAre(HasSubstr("command.run_forward: sends a motion command without a "
                                    "confirming rule")));
}

TEST(Descriptions, AMotionCommandWithoutSetpointLimitsIsRefused) {
  std::string text = kHead + kRules;
  text.replace(text.find("min = 100\nmax = 3000\n"), 21, "");
  EXPECT_THAT(errors_of(text), ElementsAre(HasSubstr("setpoint: a description that can send a "
                                                     "motion command needs setpoint limits")));
  text = kHead + kRules;
  text.replace(text.find("[setpoint]"), std::string::npos, "");
  EXPECT_THAT(errors_of(text), ElementsAre(HasSubstr("needs setpoint limits")));
}

TEST(Descriptions, AStartWithoutAStopIsRefused) {
  std::string text = kHead + kRules;
  text.replace(text.find("[[command.stop]]\nsend = \"halt\"\n"), 31, "");
  EXPECT_THAT(errors_of(text), ElementsAre(HasSubstr("must say how to stop it")));
}

TEST(Descriptions, AWritablePointNeedsLimits) {
  EXPECT_THAT(errors_of(kHead + kRules + R"(
[[point]]
name = "ramp"
table = "holding"
type = "u16"
description = "ramp time"
)"),
              ElementsAre(HasSubstr("point.ramp: a writable point needs min and max")));
}

TEST(Descriptions, NotTomlAtAll) {
  EXPECT_THAT(errors_of("[protocol\nname = 1"), ElementsAre(HasSubstr("t.toml:1: ")));
  EXPECT_THAT(errors_of(""), testing::Contains(HasSubstr("protocol: required key is missing")));
}

}  // namespace
}  // namespace drivegate::framed
