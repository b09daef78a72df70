// SVG building blocks shared by every figure: escaped text, pixel numbers, elements, the
// document frame and clip groups. A pixel coordinate is written with at most two decimals.
#pragma once

#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "physgrad/text.hpp"  // xml_escape

namespace physgrad::svg {

struct Point {
  double x, y;
};
using Polyline = std::vector<Point>;

struct Box {  // in pixels, y grows downwards
  double left, top, right, bottom;
  double width() const { return right - left; }
  double height() const { return bottom - top; }
};

// `b` grown by dx on the left and right and dy at the top and bottom.
Box grow(const Box& b, double dx, double dy);
bool inside(const Point& p, const Box& b);

// A pixel coordinate with at most two decimals: "12.5", "-3", "0". Non-finite values, which
// never belong in a figure, are written as 0.
std::string num(double v);
// Approximate width of `text` in pixels at `font_size`, counting UTF-8 code points.
double text_width(std::string_view text, double font_size = 12);

// <text x y attributes>content</text>
std::string text(double x, double y, std::string_view content, std::string_view attributes = "");
// <path d attributes/>, or nothing for empty path data.
std::string path(const std::string& d, const std::string& attributes);
// <rect> with the given box and attributes.
std::string rect(const Box& b, const std::string& attributes);
// Path data "M x y h0": a dot when stroked with round caps.
std::string dot(const Point& p);

// The document's opening tag (width × height, viewBox from 0) with a white background; close
// it with "</svg>\n".
std::string open(int width, int height);
// Documents of open() or responsive() placed side by side, tops aligned, `gap` pixels apart, as
// one document; where any is responsive, a responsive one whose narrow layout stacks the
// panels' narrow layouts. Throws Error for a text that is not such a document.
std::string side_by_side(const std::vector<std::string>& documents, int gap = 12);
// Rows of documents as side_by_side() places them, one row above the next; the narrow layout
// stacks every panel's narrow layout in reading order.
std::string grid(const std::vector<std::vector<std::string>>& rows, int gap = 12);

// A figure in two layouts, documents of open(): `wide` as it is, and `narrow` (at most
// kNarrowWidth pixels wide: panels stacked, legend below) where the screen is narrower than the
// wide one. One root <svg> of the wide size holds both as nested <svg>s; a <style> inside it
// shows the narrow one and resizes the root where the viewport is narrower than the wide one (a
// page that embeds it may move that width: switched_below). Without CSS the wide one shows.
// Throws Error for a text that is not a document of open().
inline constexpr int kNarrowWidth = 380;
std::string responsive(const std::string& wide, const std::string& narrow);
// The two layouts of a document (for a document of open(), itself twice), as documents of
// open(). Throws Error for a text that is neither.
struct Layouts {
  std::string wide, narrow;
};
Layouts layouts(const std::string& document);
// A responsive() document that switches to its narrow layout where the viewport is narrower than
// `below` pixels (e.g. embedded in a page with margins); any other document as it is.
std::string switched_below(const std::string& document, int below);
// The width and height of a document of open() or responsive() (its root's).
std::pair<int, int> size_of(const std::string& document);

// `content` clipped to the box. The clip path's id derives from what it clips, so figures
// embedded side by side in one HTML page do not pick up each other's clip paths.
std::string clipped(const Box& b, const std::string& content);

}  // namespace physgrad::svg
