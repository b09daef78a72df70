// Test helper: checks that an SVG document is well-formed XML whose drawing stays inside its view
// box — every element closed and nested properly, attribute values quoted, entities valid; path
// data of M/L/H/V/Z (absolute or relative) commands with the right count of numbers; every
// coordinate (path points, x/y/cx/cy, polygon points, translate) finite and inside the view box
// of the <svg> it is in (a nested <svg>, a figure's other layout, has its own).
#pragma once

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <map>
#include <string>
#include <tuple>
#include <vector>

namespace physgrad::testing {

class SvgChecker {
 public:
  // The problems found in `svg` (empty when it is valid), at most a few, each naming where.
  static std::vector<std::string> check(const std::string& svg) {
    SvgChecker c(svg);
    c.document();
    return c.problems_;
  }

 private:
  explicit SvgChecker(const std::string& text) : s_(text) {}

  void fail(const std::string& what) {
    if (problems_.size() < 8) problems_.push_back(what + " (at byte " + std::to_string(at_) + ")");
  }
  bool end() const { return at_ >= s_.size(); }
  void skip_space() {
    while (!end() && std::isspace(static_cast<unsigned char>(s_[at_]))) ++at_;
  }
  std::string name() {
    const std::size_t start = at_;
    while (!end() && (std::isalnum(static_cast<unsigned char>(s_[at_])) || s_[at_] == '-' ||
                      s_[at_] == ':' || s_[at_] == '_')) {
      ++at_;
    }
    return s_.substr(start, at_ - start);
  }
  // Text or an attribute value: no '<', and every '&' starts a known entity.
  void check_text(const std::string& text) {
    if (text.find('<') != std::string::npos) fail("'<' in text or attribute value");
    for (std::size_t k = text.find('&'); k != std::string::npos; k = text.find('&', k + 1)) {
      const std::size_t semi = text.find(';', k);
      const std::string entity = semi == std::string::npos ? "" : text.substr(k + 1, semi - k - 1);
      const bool numeric = entity.size() > 1 && entity[0] == '#' &&
                           entity.find_first_not_of("0123456789", 1) == std::string::npos;
      if (!numeric && entity != "amp" && entity != "lt" && entity != "gt" && entity != "quot" &&
          entity != "apos") {
        fail("unknown entity '&" + entity + "'");
      }
    }
  }

  void document() {
    skip_space();
    std::vector<std::string> open;
    bool root_seen = false;
    while (!end()) {
      if (s_[at_] != '<') {
        const std::size_t next = s_.find('<', at_);
        const std::string text = s_.substr(at_, next - at_);
        check_text(text);
        if (open.empty() && text.find_first_not_of(" \t\r\n") != std::string::npos) {
          fail("text outside the root element");
        }
        at_ = next == std::string::npos ? s_.size() : next;
        continue;
      }
      ++at_;
      if (s_.compare(at_, 3, "!--") == 0) {
        const std::size_t close = s_.find("-->", at_);
        if (close == std::string::npos) return fail("unterminated comment");
        at_ = close + 3;
        continue;
      }
      if (!end() && s_[at_] == '/') {
        ++at_;
        const std::string n = name();
        skip_space();
        if (end() || s_[at_] != '>') return fail("malformed end tag </" + n);
        ++at_;
        if (open.empty() || open.back() != n) return fail("end tag </" + n + "> does not match");
        open.pop_back();
        if (n == "svg" && !boxes_.empty()) {  // back to the enclosing <svg>'s view box
          std::tie(x0_, y0_, x1_, y1_) = boxes_.back();
          boxes_.pop_back();
        }
        continue;
      }
      const std::string n = name();
      if (n.empty()) return fail("malformed start tag");
      if (open.empty()) {
        if (root_seen) return fail("a second root element <" + n + ">");
        if (n != "svg") return fail("the root element is <" + n + ">, not <svg>");
        root_seen = true;
      }
      std::map<std::string, std::string> attributes;
      for (;;) {
        skip_space();
        if (end()) return fail("unterminated tag <" + n);
        if (s_[at_] == '>' || s_.compare(at_, 2, "/>") == 0) break;
        const std::string key = name();
        skip_space();
        if (key.empty() || end() || s_[at_] != '=') return fail("malformed attribute in <" + n);
        ++at_;
        skip_space();
        if (end() || (s_[at_] != '"' && s_[at_] != '\'')) {
          return fail("unquoted attribute " + key + " in <" + n);
        }
        const char quote = s_[at_++];
        const std::size_t close = s_.find(quote, at_);
        if (close == std::string::npos) return fail("unterminated attribute " + key);
        const std::string value = s_.substr(at_, close - at_);
        check_text(value);
        if (!attributes.emplace(key, value).second) fail("attribute " + key + " given twice");
        at_ = close + 1;
      }
      // A nested <svg> (a figure's other layout) is placed in the enclosing view box and draws
      // in a view box of its own.
      if (n == "svg" && !open.empty()) {
        check_geometry(n, attributes);
        boxes_.emplace_back(x0_, y0_, x1_, y1_);
      }
      if (n == "svg") read_view_box(attributes);
      if (n != "svg" || open.empty()) check_geometry(n, attributes);
      if (s_[at_] == '/') {
        at_ += 2;
      } else {
        ++at_;
        open.push_back(n);
      }
    }
    if (!root_seen) fail("no <svg> element");
    if (!open.empty()) fail("<" + open.back() + "> is never closed");
  }

  void read_view_box(const std::map<std::string, std::string>& a) {
    const auto it = a.find("viewBox");
    std::vector<double> v;
    if (it == a.end() || !numbers(it->second, v) || v.size() != 4 || v[2] <= 0 || v[3] <= 0) {
      return fail("an <svg> has no valid viewBox");
    }
    x0_ = v[0];
    y0_ = v[1];
    x1_ = v[0] + v[2];
    y1_ = v[1] + v[3];
  }

  // Numbers separated by spaces or commas; false on anything else or a non-finite number.
  static bool numbers(const std::string& text, std::vector<double>& out) {
    std::size_t k = 0;
    while (k < text.size()) {
      if (std::isspace(static_cast<unsigned char>(text[k])) || text[k] == ',') {
        ++k;
        continue;
      }
      std::size_t used = 0;
      if (!number_at(text, k, used)) return false;
      out.push_back(std::strtod(text.c_str() + k, nullptr));
      k += used;
    }
    return true;
  }

  // A decimal number (sign, digits, optional fraction and exponent) at text[k]; its length.
  static bool number_at(const std::string& text, std::size_t k, std::size_t& length) {
    std::size_t e = k;
    if (e < text.size() && (text[e] == '-' || text[e] == '+')) ++e;
    std::size_t digits = 0;
    const auto read_digits = [&] {
      while (e < text.size() && std::isdigit(static_cast<unsigned char>(text[e]))) {
        ++e;
        ++digits;
      }
    };
    read_digits();
    if (e < text.size() && text[e] == '.') {
      ++e;
      read_digits();
    }
    if (digits == 0) return false;
    if (e < text.size() && (text[e] == 'e' || text[e] == 'E')) {
      ++e;
      if (e < text.size() && (text[e] == '-' || text[e] == '+')) ++e;
      while (e < text.size() && std::isdigit(static_cast<unsigned char>(text[e]))) ++e;
    }
    length = e - k;
    return std::isfinite(std::strtod(text.substr(k, length).c_str(), nullptr));
  }

  void point(double x, double y, const std::string& where) {
    constexpr double kSlack = 1;
    if (!(x >= x0_ - kSlack && x <= x1_ + kSlack && y >= y0_ - kSlack && y <= y1_ + kSlack)) {
      fail(where + ": point (" + std::to_string(x) + ", " + std::to_string(y) +
           ") outside the view box");
    }
  }

  void check_geometry(const std::string& element, const std::map<std::string, std::string>& a) {
    for (const char* key : {"x", "y", "cx", "cy", "r", "width", "height", "stroke-width",
                            "font-size", "rx", "fill-opacity", "stroke-opacity"}) {
      const auto it = a.find(key);
      std::vector<double> v;
      if (it != a.end() && (!numbers(it->second, v) || v.size() != 1)) {
        fail("<" + element + "> " + key + "=\"" + it->second + "\" is not one finite number");
      }
    }
    if (element != "svg") {
      const auto get = [&](const char* key) {
        const auto it = a.find(key);
        return it == a.end() ? 0.0 : std::strtod(it->second.c_str(), nullptr);
      };
      if (a.count("x") || a.count("y")) point(get("x"), get("y"), "<" + element + "> x, y");
      if (a.count("cx")) point(get("cx"), get("cy"), "<" + element + "> cx, cy");
      if (a.count("width")) point(get("x") + get("width"), get("y") + get("height"),
                                  "<" + element + "> x + width, y + height");
    }
    if (const auto it = a.find("points"); it != a.end()) {
      std::vector<double> v;
      if (!numbers(it->second, v) || v.size() % 2 != 0) return fail("bad points of <" + element + ">");
      for (std::size_t k = 0; k + 1 < v.size(); k += 2) point(v[k], v[k + 1], "polygon");
    }
    if (const auto it = a.find("transform"); it != a.end()) {
      const std::string& t = it->second;
      const std::size_t open = t.find("translate("), close = t.find(')', open);
      std::vector<double> v;
      if (open == std::string::npos || close == std::string::npos ||
          !numbers(t.substr(open + 10, close - open - 10), v) || v.size() != 2) {
        return fail("transform \"" + t + "\" is not translate(x y) …");
      }
      point(v[0], v[1], "translate");
    }
    if (const auto it = a.find("d"); it != a.end()) path_data(it->second);
  }

  // M/m and L/l take pairs, H/h and V/v single numbers, Z/z none; nothing else is drawn here.
  void path_data(const std::string& d) {
    double x = 0, y = 0, start_x = 0, start_y = 0;
    std::size_t k = 0;
    char command = 0;
    bool any = false;
    while (k < d.size()) {
      if (std::isspace(static_cast<unsigned char>(d[k])) || d[k] == ',') {
        ++k;
        continue;
      }
      if (std::isalpha(static_cast<unsigned char>(d[k])) && d[k] != 'e' && d[k] != 'E') {
        command = d[k++];
        if (!any && command != 'M') return fail("path data does not start with M: " + d.substr(0, 40));
        any = true;
        if (command == 'Z' || command == 'z') {
          x = start_x;
          y = start_y;
        } else if (std::string("MmLlHhVv").find(command) == std::string::npos) {
          return fail(std::string("unexpected path command '") + command + "'");
        }
        continue;
      }
      std::vector<double> v;
      const std::size_t count = std::string("HhVv").find(command) != std::string::npos ? 1 : 2;
      for (std::size_t n = 0; n < count; ++n) {
        while (k < d.size() && (std::isspace(static_cast<unsigned char>(d[k])) || d[k] == ',')) ++k;
        std::size_t used = 0;
        if (k >= d.size() || !number_at(d, k, used)) {
          return fail("path data: expected a finite number at '" + d.substr(k, 20) + "'");
        }
        v.push_back(std::strtod(d.c_str() + k, nullptr));
        k += used;
      }
      switch (command) {
        case 'M': x = v[0]; y = v[1]; start_x = x; start_y = y; command = 'L'; break;
        case 'm': x += v[0]; y += v[1]; start_x = x; start_y = y; command = 'l'; break;
        case 'L': x = v[0]; y = v[1]; break;
        case 'l': x += v[0]; y += v[1]; break;
        case 'H': x = v[0]; break;
        case 'h': x += v[0]; break;
        case 'V': y = v[0]; break;
        case 'v': y += v[0]; break;
        default: return fail("numbers after a Z in path data");
      }
      point(x, y, "path");
    }
  }

  const std::string& s_;
  std::size_t at_ = 0;
  std::vector<std::tuple<double, double, double, double>> boxes_;  // of enclosing <svg>s
  double x0_ = 0, y0_ = 0, x1_ = 0, y1_ = 0;
  std::vector<std::string> problems_;
};

// How many times `needle` occurs in `text` (overlapping occurrences counted).
inline std::size_t count(const std::string& text, const std::string& needle) {
  std::size_t n = 0;
  for (auto at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++n;
  return n;
}

// True when the text contains "nan" or "inf" in any letter case (a number that is not finite).
inline bool has_non_finite_text(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text.find("nan") != std::string::npos || text.find("inf") != std::string::npos;
}

}  // namespace physgrad::testing
