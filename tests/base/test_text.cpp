// Text helpers of kg/base/text.hpp that messages across the tree share.
#include <catch2/catch.hpp>

#include <cmath>

#include "kg/base/text.hpp"

using namespace kg;

TEST_CASE("significant: printf's %g at a number of digits", "[text]") {
  CHECK(text::significant(0.123456789) == "0.123457");
  CHECK(text::significant(0.123456789, 3) == "0.123");
  CHECK(text::significant(1234567.0) == "1.23457e+06");
  CHECK(text::significant(70.0, 4) == "70");
  CHECK(text::significant(-0.5, 4) == "-0.5");
  CHECK(text::significant(HUGE_VAL) == "inf");
  CHECK(text::significant(-HUGE_VAL) == "-inf");
}

TEST_CASE("join and in_quotes", "[text]") {
  CHECK(text::join({}) == "");
  CHECK(text::join({"a"}) == "a");
  CHECK(text::join({"a", "b", "c"}) == "a, b, c");
  CHECK(text::join({"x", "y"}, " -> ") == "x -> y");
  CHECK(text::join({"", "b"}) == ", b");  // an empty item keeps its place
  CHECK(text::in_quotes("lfoot") == "'lfoot'");
}

TEST_CASE("format_double and parse_double round-trip", "[text]") {
  for (double x : {0.1, 1.0 / 3, 1e-300, 123456789.125, -2.5})
    CHECK(text::parse_double(text::format_double(x)) == x);
  CHECK(text::format_double(2.0) == "2.0");
  CHECK_FALSE(text::parse_double("nan").has_value());
  CHECK(text::lower_extension("dir/Walk.BVH") == ".bvh");
}

TEST_CASE("excerpt: short, escaped, cut at a character", "[text]") {
  CHECK(text::excerpt("lfoot") == "lfoot");
  CHECK(text::excerpt("Hüfte") == "Hüfte");                                            // UTF-8 passes through
  CHECK(text::excerpt(std::string("\xff\xfeH\0I\0", 6)) == "\\xff\\xfeH\\x00I\\x00");  // UTF-16 bytes
  CHECK(text::excerpt("a\tb\x7f") == "a\\x09b\\x7f");
  CHECK(text::excerpt("\xc3") == "\\xc3");             // a sequence cut short
  CHECK(text::excerpt("\xe2\x82x") == "\\xe2\\x82x");  // a continuation missing
  const std::string long_text(6144, '(');
  const std::string cut = text::excerpt(long_text);
  CHECK(cut == std::string(60, '(') + "... (6144 bytes)");
  CHECK(text::excerpt(long_text, 10).size() < 30);
  CHECK(text::excerpt("üüü", 3) == "üü... (6 bytes)");  // never half a character
}

TEST_CASE("in_quotes escapes and cuts what a file gave", "[text]") {
  CHECK(text::in_quotes("a\x01"
                        "b") == "'a\\x01b'");
  CHECK(text::in_quotes(std::string(6144, 'k')) == "'" + std::string(200, 'k') + "... (6144 bytes)'");
}
