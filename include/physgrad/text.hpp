// Text shown to a reader — in an HTML page, an SVG figure or a one-line message — and the code
// points that must not be shown as they are: bytes that are not UTF-8, control characters (C0,
// DEL, C1), the noncharacters U+FFFE and U+FFFF (invalid in XML) and the bidirectional controls
// U+202A–U+202E and U+2066–U+2069 (they reorder the text around them).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

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

// `text` as valid UTF-8 that shows what it holds: every byte that is not UTF-8 and every
// unshowable code point replaced by U+FFFD (�). With `lines`, tab and newline are kept.
std::string shown_text(std::string_view text, bool lines = false);

// Text for XML (SVG) and HTML, in element content and attribute values: shown_text(text, true)
// with & < > " ' escaped.
std::string xml_escape(std::string_view text);

}  // namespace physgrad
