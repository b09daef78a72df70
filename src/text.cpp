#include "physgrad/text.hpp"

#include <algorithm>
#include <cstdio>

namespace physgrad {

Utf8Char utf8_char_at(std::string_view text, std::size_t at) {
  const auto byte = [&](std::size_t k) {
    return at + k < text.size() ? static_cast<unsigned char>(text[at + k]) : 0u;
  };
  const unsigned lead = byte(0);
  if (lead < 0x80) return {lead, 1};
  // The length of the sequence, the bits its lead byte carries and the range of its second byte
  // (no overlong forms, no surrogates, nothing above U+10FFFF).
  std::size_t length = 0;
  unsigned low = 0x80, high = 0xBF;
  char32_t code_point = 0;
  if (lead >= 0xC2 && lead <= 0xDF) {
    length = 2;
    code_point = lead & 0x1F;
  } else if (lead >= 0xE0 && lead <= 0xEF) {
    length = 3;
    code_point = lead & 0x0F;
    if (lead == 0xE0) low = 0xA0;
    if (lead == 0xED) high = 0x9F;
  } else if (lead >= 0xF0 && lead <= 0xF4) {
    length = 4;
    code_point = lead & 0x07;
    if (lead == 0xF0) low = 0x90;
    if (lead == 0xF4) high = 0x8F;
  } else {
    return {kNotUtf8, 1};
  }
  for (std::size_t k = 1; k < length; ++k) {
    const unsigned next = byte(k);
    if (next < (k == 1 ? low : 0x80) || next > (k == 1 ? high : 0xBF)) return {kNotUtf8, 1};
    code_point = (code_point << 6) | (next & 0x3F);
  }
  return {code_point, length};
}

std::string_view unshowable_kind(char32_t c) {
  if (c < 0x20 || (c >= 0x7F && c <= 0x9F)) return "control character";
  if (c == 0xFFFE || c == 0xFFFF) return "noncharacter";
  if ((c >= 0x202A && c <= 0x202E) || (c >= 0x2066 && c <= 0x2069)) return "bidirectional control";
  return {};
}

std::size_t code_points(std::string_view text) {
  return static_cast<std::size_t>(std::count_if(text.begin(), text.end(), [](char c) {
    return (static_cast<unsigned char>(c) & 0xC0) != 0x80;
  }));
}

std::string text_problem(std::string_view text) {
  const auto named = [](const char* format, unsigned value) {
    char buffer[16];
    std::snprintf(buffer, sizeof buffer, format, value);
    return std::string(buffer);
  };
  for (std::size_t at = 0; at < text.size();) {
    const Utf8Char c = utf8_char_at(text, at);
    if (c.code_point == kNotUtf8) {
      return "is not valid UTF-8 (byte " + named("0x%02x", static_cast<unsigned char>(text[at])) +
             " at " + std::to_string(at) + ")";
    }
    if (const std::string_view kind = unshowable_kind(c.code_point); !kind.empty()) {
      return "contains the " + std::string(kind) + " " +
             named(c.code_point < 0x80 ? "0x%02x" : "U+%04X", c.code_point) + " at byte " +
             std::to_string(at);
    }
    at += c.length;
  }
  return {};
}

std::string shown_text(std::string_view text, bool lines) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t at = 0; at < text.size();) {
    const Utf8Char c = utf8_char_at(text, at);
    const bool kept = lines && (c.code_point == '\t' || c.code_point == '\n');
    if (c.code_point == kNotUtf8 || (!kept && !unshowable_kind(c.code_point).empty())) {
      out += "\xEF\xBF\xBD";  // U+FFFD
    } else {
      out.append(text, at, c.length);
    }
    at += c.length;
  }
  return out;
}

std::string xml_escape(std::string_view text) {
  std::string out;
  for (const char c : shown_text(text, true)) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string one_line(std::string_view text) {
  static const char* const digits = "0123456789abcdef";
  std::string line;
  line.reserve(text.size());
  for (std::size_t at = 0; at < text.size();) {
    const Utf8Char c = utf8_char_at(text, at);
    const bool shown = c.code_point != kNotUtf8 && unshowable_kind(c.code_point).empty();
    for (std::size_t k = 0; k < c.length; ++k) {
      const auto byte = static_cast<unsigned char>(text[at + k]);
      if (shown) {
        line += static_cast<char>(byte);
      } else {
        line += "\\x";
        line += digits[byte >> 4];
        line += digits[byte & 0xF];
      }
    }
    at += c.length;
  }
  return line;
}

std::string in_quotes(std::string_view value) {
  std::string text(1, '\'');
  text += one_line(value);
  text += '\'';
  return text;
}

std::string report_number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", value);
  return text;
}

std::string report_row(std::string_view name, std::string_view value) {
  return "  " + std::string(name) + std::string(name.size() < 24 ? 24 - name.size() : 1, ' ') +
         std::string(value) + "\n";
}

std::string comma_list(const std::vector<std::string>& items) {
  std::string list;
  for (const std::string& item : items) list += (list.empty() ? "" : ", ") + item;
  return list;
}

std::string unknown_name_text(std::string_view what, std::string_view name,
                              const std::vector<std::string>& known) {
  return "unknown " + std::string(what) + " " + in_quotes(name) + " (known: " +
         comma_list(known) + ")";
}

Error unknown_name_error(std::string_view what, std::string_view name,
                         const std::vector<std::string>& known) {
  return Error(unknown_name_text(what, name, known));
}

}  // namespace physgrad
