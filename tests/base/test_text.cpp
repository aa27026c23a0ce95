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

TEST_CASE("excerpt: quoted, escaped, cut with the whole length", "[text]") {
  CHECK(text::excerpt("lfemur") == "'lfemur'");
  CHECK(text::excerpt("") == "''");
  CHECK(text::excerpt(std::string("a\tb\xff\x7f", 5)) == "'a\\x09b\\xff\\x7f'");
  CHECK(text::excerpt(std::string("\0z", 2)) == "'\\x00z'");
  CHECK(text::excerpt("Tête_Épaule") == "'Tête_Épaule'");       // valid UTF-8 kept
  CHECK(text::excerpt("\xc3(") == "'\\xc3('");                  // a lead byte without its continuation
  CHECK(text::excerpt("\xc2\x85") == "'\\xc2\\x85'");           // a C1 control (U+0085)
  CHECK(text::excerpt("\xed\xa0\x80") == "'\\xed\\xa0\\x80'");  // a UTF-16 surrogate
  CHECK(text::excerpt(std::string(6144, '('), 8) == "'(((((((('... (6144 bytes)");
  CHECK(text::excerpt("abcdef", 6) == "'abcdef'");  // exactly max_chars: not cut
  CHECK(text::excerpt("abcdefg", 6) == "'abcdef'... (7 bytes)");
  // An escape counts 4 and is never split; UTF-8 characters count 1.
  CHECK(text::excerpt("ab\x01", 5) == "'ab'... (3 bytes)");
  CHECK(text::excerpt("éééé", 2) == "'éé'... (8 bytes)");
  const std::string binary(100000, '\x01');
  const std::string e = text::excerpt(binary);
  CHECK(e.size() <= 2 + 60 + 20);
  CHECK_THAT(e, Catch::EndsWith("... (100000 bytes)"));
}

TEST_CASE("in_quotes escapes and cuts what a file gave", "[text]") {
  CHECK(text::in_quotes("lfoot") == "'lfoot'");
  CHECK(text::in_quotes(std::string("\xff\xfeH\0I\0", 6)) == "'\\xff\\xfeH\\x00I\\x00'");  // UTF-16 bytes
  CHECK(text::in_quotes(std::string(6144, 'k')) == "'" + std::string(200, 'k') + "'... (6144 bytes)");
}

TEST_CASE("key_path: plain keys as they are, any other quoted and cut", "[text]") {
  CHECK(text::key_path("segments", "thigh") == "segments.thigh");
  CHECK(text::key_path("limits", "l.*(femur|tibia)") == "limits.l.*(femur|tibia)");
  CHECK(text::key_path("", "bones") == "bones");
  CHECK(text::key_path("bones", "left thigh") == "bones.'left thigh'");
  CHECK(text::key_path("bones", "") == "bones.''");
  CHECK(text::key_path("bones", "a\xff") == "bones.'a\\xff'");
  CHECK(text::key_path("bones", std::string(4000, 'x')) ==
        "bones.'" + std::string(60, 'x') + "'... (4000 bytes)");
}
