#include "physgrad/report/svg_document.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>

#include "physgrad/error.hpp"
#include "physgrad/io/hash.hpp"

namespace physgrad::svg {

Box grow(const Box& b, double dx, double dy) {
  return {b.left - dx, b.top - dy, b.right + dx, b.bottom + dy};
}

bool inside(const Point& p, const Box& b) {
  return p.x >= b.left && p.x <= b.right && p.y >= b.top && p.y <= b.bottom;
}

std::string num(double v) {
  if (!std::isfinite(v)) v = 0;
  std::array<char, 48> buf{};
  std::snprintf(buf.data(), buf.size(), "%.2f", v);
  std::string s(buf.data());
  while (s.back() == '0') s.pop_back();
  if (s.back() == '.') s.pop_back();
  return s == "-0" ? "0" : s;
}

double text_width(std::string_view text, double font_size) {
  return 0.6 * font_size * static_cast<double>(code_points(text));
}

std::string text(double x, double y, std::string_view content, std::string_view attributes) {
  std::string out = "<text x=\"" + num(x) + "\" y=\"" + num(y) + "\"";
  if (!attributes.empty()) {
    out += ' ';
    out += attributes;
  }
  return out + ">" + xml_escape(content) + "</text>\n";
}

std::string path(const std::string& d, const std::string& attributes) {
  return d.empty() ? "" : "<path d=\"" + d + "\" " + attributes + "/>\n";
}

std::string rect(const Box& b, const std::string& attributes) {
  return "<rect x=\"" + num(b.left) + "\" y=\"" + num(b.top) + "\" width=\"" +
         num(b.width()) + "\" height=\"" + num(b.height()) + "\" " + attributes + "/>\n";
}

std::string dot(const Point& p) { return std::string("M") + num(p.x) + " " + num(p.y) + "h0"; }

namespace {

std::string open_tag(int width, int height, const std::string& extra = "") {
  const std::string w = std::to_string(width), h = std::to_string(height);
  return "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + w + "\" height=\"" + h +
         "\" viewBox=\"0 0 " + w + " " + h + "\"" + extra +
         " font-family=\"Helvetica, Arial, sans-serif\" font-size=\"12\">\n";
}

constexpr std::string_view kRoot = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"";
constexpr std::string_view kWide = "<svg class=\"pg-wide\"", kNarrow = "<svg class=\"pg-narrow\"";

// What follows the opening tag of a document of open() up to its closing tag: the background and
// the drawing.
std::string body_of(const std::string& document) {
  const std::size_t tag_end = document.find(">\n");
  const std::size_t close = document.rfind("</svg>");
  if (document.rfind(kRoot, 0) != 0 || tag_end == std::string::npos ||
      close == std::string::npos || close < tag_end) {
    throw Error("svg: a figure is not an SVG document of svg::open()");
  }
  return document.substr(tag_end + 2, close - tag_end - 2);
}

// The content of the nested <svg> that starts with `marker` in a responsive() document, up to
// its closing tag (which precedes `end`).
std::string nested_body(const std::string& document, std::string_view marker,
                        std::string_view end) {
  const std::size_t at = document.find(marker);
  const std::size_t tag_end = at == std::string::npos ? at : document.find(">\n", at);
  const std::size_t stop = tag_end == std::string::npos ? tag_end : document.find(end, tag_end);
  if (stop == std::string::npos) throw Error("svg: a figure is not a responsive SVG document");
  const std::size_t close = document.rfind("</svg>\n", stop);
  return document.substr(tag_end + 2, close - tag_end - 2);
}

constexpr std::string_view kFigureClass = " class=\"pg-fig ";

bool is_responsive(const std::string& document) {
  const std::size_t tag_end = document.find(">\n");
  return document.rfind(kRoot, 0) == 0 &&
         document.substr(0, tag_end).find(kFigureClass) != std::string::npos;
}

// The narrow layout's size, and its aspect ratio, which a page that sizes the figure to its width
// (height:auto) keeps: the root's view box has the wide one's.
std::string switch_rules(const std::string& name, int width, int height) {
  const std::string w = std::to_string(width), h = std::to_string(height);
  return "svg." + name + "{width:" + w + "px;height:" + h + "px;aspect-ratio:" + w + "/" + h +
         "}svg." + name + " svg.pg-wide{display:none}svg." + name +
         " svg.pg-narrow{display:inline}";
}

}  // namespace

std::string open(int width, int height) {
  return open_tag(width, height) + "<rect width=\"" + std::to_string(width) + "\" height=\"" +
         std::to_string(height) + "\" fill=\"white\"/>\n";
}

std::pair<int, int> size_of(const std::string& document) {
  int w = 0, h = 0;
  if (document.rfind(kRoot, 0) != 0 ||
      std::sscanf(document.c_str() + kRoot.size(), "%d\" height=\"%d\"", &w, &h) != 2) {
    throw Error("svg: a figure is not an SVG document of svg::open()");
  }
  return {w, h};
}

std::string responsive(const std::string& wide, const std::string& narrow) {
  const auto [w, h] = size_of(wide);
  const auto [nw, nh] = size_of(narrow);
  const std::string wide_body = body_of(wide), narrow_body = body_of(narrow);
  std::array<char, 24> id{};
  std::snprintf(id.data(), id.size(), "pg-f%016llx",
                static_cast<unsigned long long>(fnv1a64(wide_body + narrow_body)));
  const std::string name = id.data();
  const std::string box = " x=\"0\" y=\"0\" width=\"" + std::to_string(w) + "\" height=\"" +
                          std::to_string(h) + "\" preserveAspectRatio=\"none\" viewBox=\"0 0 ";
  return open_tag(w, h,
                  " preserveAspectRatio=\"none\" class=\"pg-fig " + name + "\" data-narrow=\"" +
                      std::to_string(nw) + " " + std::to_string(nh) + "\"") +
         "<style>svg." + name + " svg.pg-narrow{display:none}@media (max-width:" +
         std::to_string(w - 1) + "px){" + switch_rules(name, nw, nh) + "}</style>\n" +
         std::string(kWide) + box + std::to_string(w) + " " + std::to_string(h) + "\">\n" +
         wide_body + "</svg>\n" + std::string(kNarrow) + " display=\"none\"" + box +
         std::to_string(nw) + " " + std::to_string(nh) + "\">\n" + narrow_body + "</svg>\n</svg>\n";
}

Layouts layouts(const std::string& document) {
  if (!is_responsive(document)) {
    body_of(document);  // checks it
    return {document, document};
  }
  const auto [w, h] = size_of(document);
  const std::size_t at = document.find("data-narrow=\"");
  int nw = 0, nh = 0;
  if (at == std::string::npos || std::sscanf(document.c_str() + at + 13, "%d %d", &nw, &nh) != 2) {
    throw Error("svg: a figure is not a responsive SVG document");
  }
  return {open_tag(w, h) + nested_body(document, kWide, kNarrow) + "</svg>\n",
          open_tag(nw, nh) + nested_body(document, kNarrow, "</svg>\n</svg>") + "</svg>\n"};
}

std::string switched_below(const std::string& document, int below) {
  if (!is_responsive(document)) return document;
  // responsive() writes one "@media (max-width:Npx)" in its <style>: N becomes below − 1.
  constexpr std::string_view kQuery = "@media (max-width:";
  const std::size_t style_end = document.find("</style>");
  const std::size_t at = document.find(kQuery);
  const std::size_t end = at == std::string::npos ? at : document.find("px)", at);
  if (end == std::string::npos || end > style_end) {
    throw Error("svg: a figure is not a responsive SVG document");
  }
  std::string out = document;
  out.replace(at + kQuery.size(), end - at - kQuery.size(), std::to_string(std::max(0, below - 1)));
  return out;
}

namespace {

// Documents of open() side by side (or stacked), `gap` pixels apart, as one document of open().
std::string arranged(const std::vector<std::string>& documents, int gap, bool stacked) {
  std::string body;
  int width = 0, height = 0;
  for (const std::string& document : documents) {
    const auto [w, h] = size_of(document);
    const std::string content = body_of(document);
    // open() writes its white background right after the opening tag: drop it.
    const std::size_t background = content.find("/>\n");
    int& along = stacked ? height : width;
    if (along > 0) along += gap;
    body += "<g transform=\"translate(" + std::to_string(stacked ? 0 : width) + " " +
            std::to_string(stacked ? height : 0) + ")\">\n" + content.substr(background + 3) +
            "</g>\n";
    along += stacked ? h : w;
    int& across = stacked ? width : height;
    across = std::max(across, stacked ? w : h);
  }
  return open(width, height) + body + "</svg>\n";
}

}  // namespace

std::string side_by_side(const std::vector<std::string>& documents, int gap) {
  return grid({documents}, gap);
}

std::string grid(const std::vector<std::vector<std::string>>& rows, int gap) {
  std::vector<std::string> wide_rows, narrow;
  bool any_responsive = false;
  for (const std::vector<std::string>& row : rows) {
    std::vector<std::string> wide;
    for (const std::string& document : row) {
      any_responsive = any_responsive || is_responsive(document);
      Layouts both = layouts(document);
      wide.push_back(std::move(both.wide));
      narrow.push_back(std::move(both.narrow));
    }
    wide_rows.push_back(arranged(wide, gap, false));
  }
  // One row is that row itself, not a stack of one.
  const std::string wide = wide_rows.size() == 1 ? wide_rows[0] : arranged(wide_rows, gap, true);
  if (!any_responsive && size_of(wide).first <= kNarrowWidth) return wide;
  return responsive(wide, arranged(narrow, gap, true));
}

std::string clipped(const Box& b, const std::string& content) {
  const std::string box = "x=\"" + num(b.left) + "\" y=\"" + num(b.top) + "\" width=\"" +
                          num(b.width()) + "\" height=\"" + num(b.height()) + "\"";
  std::array<char, 24> id{};
  std::snprintf(id.data(), id.size(), "clip%016llx",
                static_cast<unsigned long long>(fnv1a64(box + content)));
  return "<defs><clipPath id=\"" + std::string(id.data()) + "\"><rect " + box +
         "/></clipPath></defs>\n<g clip-path=\"url(#" + id.data() + ")\">\n" + content + "</g>\n";
}

}  // namespace physgrad::svg
