// Text — the one rule for text a reader sees (a page, a figure, a one-line message) and the
// helpers every message uses: which code points cannot be shown as they are, how each place
// shows them, quoting a value, and "unknown WHAT 'NAME' (known: a, b, c)".
//
// Not shown as they are: bytes that are not UTF-8, control characters (C0, DEL, C1), the
// noncharacters U+FFFE and U+FFFF (invalid in XML) and the bidirectional controls U+202A–U+202E
// and U+2066–U+2069 (they reorder the text around them). A value given by a user is refused when
// it holds any (text_problem); text read back from files is shown with U+FFFD in their place in
// pages (shown_text, xml_escape) and with their bytes as \xNN in messages (one_line, quoted).
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "physgrad/error.hpp"

namespace physgrad {

// One UTF-8 sequence at text[at]: its code point and its length in bytes. A byte that does not
// start a valid sequence (a continuation byte, an overlong form, a surrogate, a code point beyond
// U+10FFFF, a sequence cut short) gives kNotUtf8 and length 1.
struct Utf8Char {
  char32_t code_point;
  std::size_t length;
};
inline constexpr char32_t kNotUtf8 = 0xFFFFFFFF;
Utf8Char utf8_char_at(std::string_view text, std::size_t at);

// What keeps code point `c` from being shown as it is — "control character", "noncharacter" or
// "bidirectional control" — or empty when nothing does.
std::string_view unshowable_kind(char32_t c);

// The number of code points of UTF-8 `text` (bytes that are not continuation bytes): what a
// terminal column or a figure's text width counts.
std::size_t code_points(std::string_view text);

// Empty when `text` is valid UTF-8 that shows what it holds; else what is wrong with it, e.g.
// "contains the control character 0x00 at byte 6", "contains the bidirectional control U+202E
// at byte 4" or "is not valid UTF-8 (byte 0xff at 2)".
std::string text_problem(std::string_view text);

// `text` as valid UTF-8 that shows what it holds: every byte that is not UTF-8 and every
// unshowable code point replaced by U+FFFD (�). With `lines`, tab and newline are kept.
std::string shown_text(std::string_view text, bool lines = false);

// Text for XML (SVG) and HTML, in element content and attribute values: shown_text(text, true)
// with & < > " ' escaped.
std::string xml_escape(std::string_view text);

// `text` for a one-line message: every byte of what cannot be shown (a newline in a value, a
// byte that is not UTF-8) written as \xNN, so the reader sees exactly which bytes the value has.
std::string one_line(std::string_view text);

// A value named in a message: 'VALUE', as one_line() shows it.
std::string in_quotes(std::string_view value);

// "a, b, c".
std::string comma_list(const std::vector<std::string>& items);

// A number in a report: printf's %.6g ("0.001", "1.5e+03").
std::string report_number(double value);
// One line of a multi-line report: "  NAME", padded to 26 columns (at least one space), VALUE.
std::string report_row(std::string_view name, std::string_view value);

// Error "unknown WHAT 'NAME' (known: a, b, c)", e.g. unknown_name_error("experiment", "x",
// {"scaled-toy", …}); unknown_name_text() is its message, for one with a prefix.
std::string unknown_name_text(std::string_view what, std::string_view name,
                              const std::vector<std::string>& known);
Error unknown_name_error(std::string_view what, std::string_view name,
                         const std::vector<std::string>& known);

// The names of an enum's values, {{Enum::kA, "a"}, …}: name_of() and value_named() read it both
// ways.
template <class Enum, std::size_t N>
using NameTable = std::array<std::pair<Enum, const char*>, N>;

// The name of `value`; throws Error "to_string: invalid WHAT value 7" for a value the table lacks
// (a number cast to the enum).
template <class Enum, std::size_t N>
std::string name_of(const NameTable<Enum, N>& names, Enum value, std::string_view what) {
  for (const auto& [candidate, name] : names) {
    if (candidate == value) return name;
  }
  throw Error("to_string: invalid " + std::string(what) + " value " +
              std::to_string(static_cast<long long>(value)));
}

// The value named `text`; throws unknown_name_error(what, text, every name of the table).
template <class Enum, std::size_t N>
Enum value_named(const NameTable<Enum, N>& names, std::string_view text, std::string_view what) {
  std::vector<std::string> known;
  for (const auto& [value, name] : names) {
    if (text == name) return value;
    known.emplace_back(name);
  }
  throw unknown_name_error(what, text, known);
}

}  // namespace physgrad
