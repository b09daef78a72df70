// The one text rule (physgrad/text.hpp): what is shown of a text in pages and in messages, and
// the messages naming an unknown name.
#include "physgrad/text.hpp"

#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

namespace physgrad {
namespace {

TEST(ShownText, EscapesForXmlAndReplacesWhatCannotBeShown) {
  EXPECT_EQ(xml_escape("a<b>&\"c'"), "a&lt;b&gt;&amp;&quot;c&#39;");
  const std::string replaced = "\xef\xbf\xbd";  // U+FFFD
  // Multi-byte characters (λ, €, 𝑥) and U+FFFD itself are kept; tab and newline in XML text.
  EXPECT_EQ(xml_escape("λ € \xf0\x9d\x91\xa5 \xef\xbf\xbd\tx\ny"),
            "λ € \xf0\x9d\x91\xa5 \xef\xbf\xbd\tx\ny");
  EXPECT_EQ(shown_text("a\tb\nc"), "a" + replaced + "b" + replaced + "c");
  EXPECT_EQ(shown_text("a\tb\nc", true), "a\tb\nc");
  // Each byte that does not start a valid UTF-8 sequence, and each unshowable character, becomes
  // one U+FFFD: (text, how many).
  const std::vector<std::pair<std::string, std::size_t>> cases = {
      {"\xff", 1},
      {"\x80", 1},
      {"\xc0\xaf", 2},          // stray bytes, an overlong form
      {"\xed\xa0\x80", 3},      // a surrogate
      {"\xf4\x90\x80\x80", 4},  // beyond U+10FFFF
      {"\xe2\x82", 2},          // cut short
      {"\x01", 1},
      {"\r", 1},
      {"\x7f", 1},
      {"\xc2\x85", 1},  // C0, DEL, C1
      {"\xef\xbf\xbe", 1},
      {"\xef\xbf\xbf", 1},  // U+FFFE, U+FFFF
      {"\xe2\x80\xaa", 1},
      {"\xe2\x80\xae", 1},  // U+202A, U+202E
      {"\xe2\x81\xa6", 1},
      {"\xe2\x81\xa9", 1}};  // U+2066, U+2069
  for (const auto& [bad, count] : cases) {
    std::string replacements;
    for (std::size_t k = 0; k < count; ++k) replacements += replaced;
    EXPECT_EQ(xml_escape("<" + bad + ">"), "&lt;" + replacements + "&gt;") << bad;
    EXPECT_EQ(shown_text(bad, true), replacements) << bad;
  }
  // U+202F and U+2065, next to the bidirectional controls, are kept.
  EXPECT_EQ(shown_text("\xe2\x80\xae"
                       "ab\xe2\x80\xaf"
                       "c\xe2\x81\xa5"),
            replaced +
                "ab\xe2\x80\xaf"
                "c\xe2\x81\xa5");
}

TEST(Text, OneLineWritesTheBytesOfWhatCannotBeShown) {
  EXPECT_EQ(one_line("plain λ ≤ 1"), "plain λ ≤ 1");
  EXPECT_EQ(one_line("a\nb\tc\x7f"), "a\\x0ab\\x09c\\x7f");
  EXPECT_EQ(one_line("\xc2\x85"), "\\xc2\\x85");               // C1 control
  EXPECT_EQ(one_line("\xe2\x80\xae" "ab"), "\\xe2\\x80\\xaeab");  // U+202E
  EXPECT_EQ(one_line("x\xff"), "x\\xff");                       // not UTF-8
  EXPECT_EQ(one_line(std::string("a\0b", 3)), "a\\x00b");
  EXPECT_EQ(in_quotes("run\n1"), "'run\\x0a1'");
  // One rule: what one_line() escapes is what text_problem() names and shown_text() replaces.
  for (const std::string bad : {"\x01", "\xc2\x85", "\xef\xbf\xbe", "\xe2\x81\xa6", "\xff"}) {
    EXPECT_NE(one_line(bad), bad);
    EXPECT_FALSE(text_problem(bad).empty()) << one_line(bad);
    EXPECT_EQ(shown_text(bad), "\xef\xbf\xbd") << one_line(bad);
  }
}

TEST(Text, NamesTheProblemOfAGivenValue) {
  EXPECT_EQ(text_problem("λ = 0.01"), "");
  EXPECT_EQ(text_problem("victim\n"), "contains the control character 0x0a at byte 6");
  EXPECT_EQ(text_problem("ab\xe2\x80\xae"), "contains the bidirectional control U+202E at byte 2");
  EXPECT_EQ(text_problem("a\xff"), "is not valid UTF-8 (byte 0xff at 1)");
}

TEST(Text, CountsCodePoints) {
  EXPECT_EQ(code_points(""), 0u);
  EXPECT_EQ(code_points("α ≤ 1"), 5u);
  EXPECT_EQ(code_points("\xf0\x9d\x91\xa5"), 1u);
}

enum class Colour { kRed, kBlue };
constexpr NameTable<Colour, 2> kColours{{{Colour::kRed, "red"}, {Colour::kBlue, "blue"}}};

TEST(Text, UnknownNamesAreRefusedWithTheKnownOnes) {
  EXPECT_STREQ(unknown_name_error("experiment", "x\ny", {"a", "b"}).what(),
               "unknown experiment 'x\\x0ay' (known: a, b)");
  EXPECT_EQ(unknown_name_text("rule", "", {}), "unknown rule '' (known: )");
  EXPECT_EQ(comma_list({"a", "b", "c"}), "a, b, c");
  EXPECT_EQ(value_named(kColours, "blue", "colour"), Colour::kBlue);
  EXPECT_EQ(name_of(kColours, Colour::kRed, "Colour"), "red");
  try {
    name_of(kColours, static_cast<Colour>(7), "Colour");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "to_string: invalid Colour value 7");
  }
  try {
    value_named(kColours, "green", "colour");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "unknown colour 'green' (known: red, blue)");
  }
}

}  // namespace
}  // namespace physgrad
