#include "tachi/common/csv.hpp"

#include <gtest/gtest.h>

#include <sstream>

namespace tachi::common {
namespace {

TEST(CsvReader, FindsColumnsByHeaderName) {
  std::istringstream in("frame,x,y\n1,2,3\n");
  CsvReader csv(in);
  EXPECT_EQ(csv.column("frame"), 0U);
  EXPECT_EQ(csv.column("y"), 2U);
  EXPECT_FALSE(csv.column("z").has_value());
  EXPECT_FALSE(csv.column("X").has_value());  // names are case-sensitive
}

TEST(CsvReader, TrimsCellsAndDropsWindowsLineEnds) {
  std::istringstream in(" t , x\r\n 1.5 ,\t2 \r\n3,\r\n");
  CsvReader csv(in);
  EXPECT_EQ(csv.header(), (std::vector<std::string>{"t", "x"}));
  const auto first = csv.next();
  ASSERT_TRUE(first);
  EXPECT_EQ(first->cells, (std::vector<std::string>{"1.5", "2"}));
  const auto second = csv.next();
  ASSERT_TRUE(second);
  EXPECT_EQ(second->cells, (std::vector<std::string>{"3", ""}));  // a trailing comma is an empty cell
}

TEST(CsvReader, SkipsBlankLinesAndKeepsLineNumbers) {
  std::istringstream in("\n  \na,b\n\n1,2\r\n \t\n3,4");
  CsvReader csv(in);
  EXPECT_EQ(csv.column("b"), 1U);
  const auto first = csv.next();
  ASSERT_TRUE(first);
  EXPECT_EQ(first->line, 5U);
  const auto second = csv.next();
  ASSERT_TRUE(second);
  EXPECT_EQ(second->line, 7U);
  EXPECT_FALSE(csv.next());

  std::istringstream empty("\n\r\n");
  EXPECT_TRUE(CsvReader(empty).header().empty());
}

TEST(CsvReader, DoesNotSupportQuotedFields) {
  // Documented in csv.hpp: a quote is an ordinary character.
  EXPECT_EQ(split_csv_line("\"a,b\",c"), (std::vector<std::string>{"\"a", "b\"", "c"}));
}

TEST(CsvCell, ParsesWholeNumbersOrNothing) {
  EXPECT_EQ(to_int64("-42"), -42);
  EXPECT_FALSE(to_int64("4.2"));
  EXPECT_FALSE(to_int64(""));
  EXPECT_FALSE(to_int64("12abc"));
  EXPECT_EQ(to_uint64("18446744073709551615"), 18446744073709551615ULL);
  EXPECT_FALSE(to_uint64("-1"));
  EXPECT_DOUBLE_EQ(*to_double("-0.25"), -0.25);
  EXPECT_DOUBLE_EQ(*to_double("+1e3"), 1000.0);
  EXPECT_FALSE(to_double("+-1"));
  EXPECT_FALSE(to_double("abc"));
  EXPECT_FALSE(to_double("1.5x"));
  EXPECT_FALSE(to_double("nan"));
  EXPECT_FALSE(to_double("inf"));
  EXPECT_FLOAT_EQ(*to_float("0.5"), 0.5F);
  EXPECT_FALSE(to_float("1e50"));  // out of float range
}

TEST(CsvCell, ParsesFlags) {
  EXPECT_EQ(to_bool("1"), true);
  EXPECT_EQ(to_bool("true"), true);
  EXPECT_EQ(to_bool("0"), false);
  EXPECT_EQ(to_bool("false"), false);
  EXPECT_FALSE(to_bool("2"));
  EXPECT_FALSE(to_bool("yes"));
}

}  // namespace
}  // namespace tachi::common
