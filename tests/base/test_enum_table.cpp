// enum_table.hpp: one table per enum, read both ways.
#include "naneye/base/enum_table.hpp"

#include <gtest/gtest.h>

using namespace naneye::base;

namespace {

enum class Color { red, green, blue };
constexpr EnumTable<Color, 4> kColorNames{
    {{Color::red, "red"}, {Color::green, "green"}, {Color::blue, "blue"}, {Color::green, "verde"}}};

}  // namespace

TEST(EnumTable, NamesEachValueByItsFirstName) {
  EXPECT_STREQ(enum_name(kColorNames, Color::red), "red");
  EXPECT_STREQ(enum_name(kColorNames, Color::green), "green");
  EXPECT_STREQ(enum_name(kColorNames, static_cast<Color>(7)), "unknown");
  EXPECT_STREQ(enum_name(kColorNames, static_cast<Color>(7), "?"), "?");
  static_assert(std::string_view(enum_name(kColorNames, Color::blue)) == "blue");
}

TEST(EnumTable, ParsesEveryNameAndAlias) {
  EXPECT_EQ(enum_parse(kColorNames, "blue"), Color::blue);
  EXPECT_EQ(enum_parse(kColorNames, "verde"), Color::green);
  EXPECT_FALSE(enum_parse(kColorNames, "Blue"));
  EXPECT_FALSE(enum_parse(kColorNames, ""));
}

TEST(EnumTable, ListsTheNamesWithoutAliases) {
  EXPECT_EQ(enum_names(kColorNames), "red, green, blue");
  EXPECT_EQ(enum_names(kColorNames, "|"), "red|green|blue");
}
