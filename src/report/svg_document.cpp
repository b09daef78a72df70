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

std::string open(int width, int height) {
  const std::string w = std::to_string(width), h = std::to_string(height);
  return "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + w + "\" height=\"" + h +
         "\" viewBox=\"0 0 " + w + " " + h +
         "\" font-family=\"Helvetica, Arial, sans-serif\" font-size=\"12\">\n"
         "<rect width=\"" +
         w + "\" height=\"" + h + "\" fill=\"white\"/>\n";
}

std::string side_by_side(const std::vector<std::string>& documents, int gap) {
  std::string body;
  int width = 0, height = 0;
  for (const std::string& document : documents) {
    // open() writes the size first and the white background right after the opening tag.
    int w = 0, h = 0;
    const std::size_t tag_end = document.find(">\n");
    const std::size_t background = document.find("/>\n", tag_end);
    const std::size_t close = document.rfind("</svg>");
    if (document.rfind("<svg ", 0) != 0 || tag_end == std::string::npos ||
        background == std::string::npos || close == std::string::npos ||
        std::sscanf(document.c_str(), "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" "
                                      "height=\"%d\"", &w, &h) != 2) {
      throw Error("side_by_side: a figure is not an SVG document of svg::open()");
    }
    if (width > 0) width += gap;
    body += "<g transform=\"translate(" + std::to_string(width) + " 0)\">\n" +
            document.substr(background + 3, close - background - 3) + "</g>\n";
    width += w;
    height = std::max(height, h);
  }
  return open(width, height) + body + "</svg>\n";
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
