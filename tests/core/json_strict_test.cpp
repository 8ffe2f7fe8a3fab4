// json_strict: nesting limit, duplicate keys, printable messages, checked numbers.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>
#include <string>

#include "qs/core/error.h"
#include "qs/core/json_strict.h"

using ::testing::HasSubstr;
namespace js = qs::json_strict;

namespace {

std::string message_of(const std::string& text) {
  try {
    (void)js::parse(text, "doc.json");
  } catch (const qs::InvalidInput& e) {
    return e.what();
  }
  return "";
}

TEST(JsonStrict, DeepNestingIsRefusedBeforeParsing) {
  EXPECT_THAT(message_of(std::string(100000, '[')), HasSubstr("nested more than 64"));
  // Brackets inside strings do not count.
  EXPECT_NO_THROW((void)js::parse("{\"a\": \"" + std::string(1000, '[') + "\"}", "doc.json"));
  std::string ok = std::string(64, '[') + std::string(64, ']');
  EXPECT_NO_THROW((void)js::parse(ok, "doc.json"));
}

TEST(JsonStrict, RepeatedKeysAreErrorsAtAnyDepth) {
  EXPECT_THAT(message_of(R"({"a": 1, "a": 2})"), HasSubstr("\"a\" appears twice"));
  EXPECT_THAT(message_of(R"({"x": [{"b": 1, "c": {"d": 1, "d": 1}}]})"), HasSubstr("\"d\""));
  EXPECT_NO_THROW((void)js::parse(R"({"a": {"a": 1}, "b": [{"a": 1}, {"a": 2}]})", "doc.json"));
}

TEST(JsonStrict, SyntaxErrorsNameTheByteAndStayPrintable) {
  const std::string m = message_of("{\"a\": \xff\xfe}");
  EXPECT_THAT(m, HasSubstr("doc.json: not valid JSON at byte"));
  EXPECT_TRUE(js::is_clean_text(m)) << m;
}

TEST(JsonStrict, PrintableEscapesBadBytesAndCuts) {
  EXPECT_EQ(js::printable("caf\xc3\xa9"), "caf\xc3\xa9");  // valid UTF-8 is kept
  EXPECT_EQ(js::printable("n\xe9z"), "n\\xe9z");           // Latin-1 is not UTF-8
  EXPECT_EQ(js::printable("a\nb"), "a\\x0ab");
  EXPECT_EQ(js::printable("\xc0\x80"), "\\xc0\\x80");      // overlong
  EXPECT_EQ(js::printable(std::string(1000, 'x'), 10), std::string(10, 'x') + "...");
}

TEST(JsonStrict, NumbersAreCheckedWithoutWrapping) {
  long long x = 0;
  EXPECT_FALSE(js::integer_in(nlohmann::json::parse("18446744073709551615"), 0, 1LL << 62, x));
  EXPECT_FALSE(js::integer_in(nlohmann::json::parse("3.0"), 0, 10, x));
  EXPECT_FALSE(js::integer_in(nlohmann::json::parse("-1"), 0, 10, x));
  EXPECT_TRUE(js::integer_in(nlohmann::json::parse("7"), 0, 10, x));
  EXPECT_EQ(x, 7);
  double d = 0;
  EXPECT_FALSE(js::finite_number(nlohmann::json(std::numeric_limits<double>::infinity()), d));
  EXPECT_FALSE(js::finite_number(nlohmann::json(std::numeric_limits<double>::quiet_NaN()), d));
  // nlohmann refuses 1e400 while parsing; parse() turns that into InvalidInput.
  EXPECT_THAT(message_of(R"({"a": 1e400})"), HasSubstr("doc.json: not valid JSON"));
  EXPECT_FALSE(js::finite_number(nlohmann::json::parse("\"1\""), d));
  EXPECT_TRUE(js::finite_number(nlohmann::json::parse("1e300"), d));
}

TEST(JsonStrict, DescribeIsShort) {
  nlohmann::json big = nlohmann::json::array();
  for (int i = 0; i < 100000; ++i) big.push_back(i);
  EXPECT_EQ(js::describe(big), "an array of 100000 values");
  EXPECT_LT(js::describe(std::string(100000, 'a')).size(), 100u);
}

}  // namespace
