// The expressions of a description (expression.h): every operator, the functions and tables, the
// names resolved when compiled, and what a bad expression is told.
#include "expression.h"

#include <gtest/gtest.h>

#include <deque>
#include <map>
#include <string>

namespace drivegate::framed {
namespace {

class ExpressionTest : public ::testing::Test {
 protected:
  ExpressionTest() {
    names_.value = [this](std::string_view id) -> std::optional<Slot> {
      if (id == "x") return Slot{Space::var, 0};
      if (id == "y") return Slot{Space::var, 1};
      if (id == "mode") return Slot{Space::var, 2};
      if (id == "f") return Slot{Space::field, 0};
      if (id == "sent.f") return Slot{Space::sent, 0};
      return std::nullopt;
    };
    names_.table = [this](std::string_view id) -> const std::vector<double>* {
      return id == "rpm" ? &rpm_ : nullptr;
    };
    names_.text = [this](std::string_view s) {
      texts_.emplace_back(s);
      return &texts_.back();
    };
    vars_ = {Val::of(10), Val::of(3), Val{0, &continuous_}};
  }
  double eval(const std::string& text) {
    std::string error;
    const auto e = Expr::compile(text, names_, error);
    EXPECT_TRUE(e.has_value()) << text << ": " << error;
    if (!e) return -999;
    const double fields[] = {7};
    const double sent[] = {5};
    return e->num({vars_, fields, sent});
  }
  std::string error_of(const std::string& text) {
    std::string error;
    EXPECT_FALSE(Expr::compile(text, names_, error).has_value()) << text;
    return error;
  }

  Names names_;
  std::vector<double> rpm_ = {0, 18, 36, 54, 72};
  std::deque<std::string> texts_;
  std::string continuous_ = "continuous";
  std::vector<Val> vars_;
};

TEST_F(ExpressionTest, ArithmeticAndPrecedence) {
  EXPECT_EQ(eval("1 + 2 * 3"), 7);
  EXPECT_EQ(eval("(1 + 2) * 3"), 9);
  EXPECT_EQ(eval("x - y - 1"), 6);  // left to right
  EXPECT_EQ(eval("x / 4"), 2.5);
  EXPECT_EQ(eval("x % 4"), 2);
  EXPECT_EQ(eval("-x + +y"), -7);
  EXPECT_EQ(eval("0.001 * 2500"), 2.5);
  EXPECT_EQ(eval("x / 0"), 0);  // never a crash, never infinity
  EXPECT_EQ(eval("x % 0"), 0);
  EXPECT_EQ(eval("-9.3e18 % -1"), 0);  // the smallest int64 by -1 would trap
}

TEST_F(ExpressionTest, BitsShiftsAndLogic) {
  EXPECT_EQ(eval("0xA5 & 0x0F"), 5);
  EXPECT_EQ(eval("0x01 | 0x80"), 0x81);
  EXPECT_EQ(eval("0xFF ^ 0x0F"), 0xF0);
  EXPECT_EQ(eval("1 << 8 | 3"), 0x103);  // shifts bind tighter than |
  EXPECT_EQ(eval("0b1010 >> 1"), 5);
  EXPECT_EQ(eval("~0 & 0xFF"), 255);
  EXPECT_EQ(eval("x > 5 && y < 5"), 1);
  EXPECT_EQ(eval("x > 50 || y != 3"), 0);
  EXPECT_EQ(eval("!x"), 0);
  EXPECT_EQ(eval("x & 2 == 2"), 0);  // == binds tighter than &, as in C: x & 1
  EXPECT_EQ(eval("(x & 2) == 2"), 1);
  EXPECT_EQ(eval("x >= 10 ? 1 : 2"), 1);
  EXPECT_EQ(eval("x < 10 ? 1 : y == 3 ? 3 : 4"), 3);
}

TEST_F(ExpressionTest, FunctionsTablesFieldsAndTexts) {
  EXPECT_EQ(eval("min(x, y, 7)"), 3);
  EXPECT_EQ(eval("max(x, y)"), 10);
  EXPECT_EQ(eval("abs(y - x)"), 7);
  EXPECT_EQ(eval("round(2.5)"), 3);  // halves away from zero
  EXPECT_EQ(eval("round(-2.5)"), -3);
  EXPECT_EQ(eval("floor(2.7) + ceil(2.1)"), 5);
  EXPECT_EQ(eval("clamp(x, 0, 5)"), 5);
  EXPECT_EQ(eval("is_run(1) + is_run(2) + is_run(3)"), 2);
  EXPECT_EQ(eval("bit(0x08, 3)"), 1);
  EXPECT_EQ(eval("rpm[2]"), 36);
  EXPECT_EQ(eval("rpm[9]"), 0);  // outside the table
  EXPECT_EQ(eval("len(rpm)"), 5);
  EXPECT_EQ(eval("nearest(rpm, 40, 0, 4)"), 2);
  EXPECT_EQ(eval("nearest(rpm, 27, 0, 4)"), 1);  // a tie takes the lower
  EXPECT_EQ(eval("nearest(rpm, 0, 3, 4)"), 3);   // only within the range
  EXPECT_EQ(eval("f + sent.f"), 12);
  EXPECT_EQ(eval("mode == 'continuous' ? 0xFF : 0x01"), 0xFF);
  EXPECT_EQ(eval("mode != 'normal'"), 1);
}

TEST_F(ExpressionTest, ConstantsAreKnownAtLoad) {
  std::string error;
  EXPECT_EQ(Expr::compile("42", names_, error)->constant(), 42);
  EXPECT_EQ(Expr::compile("-3", names_, error)->constant(), -3);
  EXPECT_FALSE(Expr::compile("x", names_, error)->constant().has_value());
  EXPECT_EQ(Expr::number(2.5).num({}), 2.5);
}

TEST_F(ExpressionTest, EveryMistakeIsNamedWithItsColumn) {
  EXPECT_EQ(error_of("speed * 2"), "unknown name 'speed' at column 7 of 'speed * 2'");
  EXPECT_EQ(error_of("x +"), "expression ends too early at column 4 of 'x +'");
  EXPECT_EQ(error_of("(x"), "expected ')' at column 3 of '(x'");
  EXPECT_EQ(error_of("x ? 1"), "expected ':' at column 6 of 'x ? 1'");
  EXPECT_EQ(error_of("sqrt(x)"), "unknown function 'sqrt' at column 6 of 'sqrt(x)'");
  EXPECT_EQ(error_of("min(x)"), "min() takes 2..8 arguments at column 7 of 'min(x)'");
  EXPECT_EQ(error_of("codes[1]"), "no table 'codes' at column 6 of 'codes[1]'");
  EXPECT_EQ(error_of("x y"), "unexpected 'y' at column 3 of 'x y'");
  EXPECT_EQ(error_of("12abc"), "bad number at column 3 of '12abc'");
  EXPECT_EQ(error_of("'open"), "unterminated text at column 1 of ''open'");
  EXPECT_EQ(error_of(""), "empty expression at column 1 of ''");
  EXPECT_NE(error_of(std::string(200, '(') + "1" + std::string(200, ')')).find("nested"),
            std::string::npos);
}

}  // namespace
}  // namespace drivegate::framed
