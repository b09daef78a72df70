#include "physgrad/report/plot_marks.hpp"

#include <array>
#include <cstdio>

#include "physgrad/text.hpp"

namespace physgrad::plot {

using svg::num;

std::string short_number(double v) {
  std::array<char, 32> buf{};
  std::snprintf(buf.data(), buf.size(), "%.4g", v);
  return buf.data();
}

std::string marker_path(int shape, const svg::Point& p, double size) {
  const double r = size / 2;
  switch (((shape % kShapes) + kShapes) % kShapes) {
    case 1:  // □
      return std::string("M") + num(p.x - r) + " " + num(p.y - r) + "h" + num(size) + "v" + num(size) + "h" +
             num(-size) + "Z";
    case 2:  // △
      return std::string("M") + num(p.x) + " " + num(p.y - 1.2 * r) + "L" + num(p.x + 1.1 * r) + " " +
             num(p.y + 0.9 * r) + "H" + num(p.x - 1.1 * r) + "Z";
    case 3:  // ◇
      return std::string("M") + num(p.x) + " " + num(p.y - 1.3 * r) + "L" + num(p.x + 1.3 * r) + " " +
             num(p.y) + "L" + num(p.x) + " " + num(p.y + 1.3 * r) + "L" + num(p.x - 1.3 * r) +
             " " + num(p.y) + "Z";
    case 4:  // ▽
      return std::string("M") + num(p.x) + " " + num(p.y + 1.2 * r) + "L" + num(p.x + 1.1 * r) + " " +
             num(p.y - 0.9 * r) + "H" + num(p.x - 1.1 * r) + "Z";
    default:
      return svg::dot(p);
  }
}

std::string markers_svg(const std::vector<svg::Polyline>& pieces, const svg::Box& bounds,
                        int shape, double size, const std::string& color, std::size_t every,
                        std::size_t offset) {
  std::string d;
  std::size_t k = 0;
  for (const svg::Polyline& piece : pieces) {
    for (const svg::Point& p : piece) {
      const bool chosen = every <= 1 || k % every == offset % every;
      ++k;
      if (chosen && svg::inside(p, bounds)) d += marker_path(shape, p, size);
    }
  }
  if (shape % kShapes == 0) {
    return svg::path(d, "stroke=\"" + color + "\" stroke-width=\"" + num(size) +
                            "\" stroke-linecap=\"round\" class=\"marker\" data-shape=\"0\"");
  }
  return svg::path(d, "fill=\"white\" stroke=\"" + color +
                          "\" stroke-width=\"1.6\" class=\"marker\" data-shape=\"" +
                          std::to_string(shape % kShapes) + "\"");
}

std::string hover_targets(const std::vector<HoverPoint>& points, const svg::Box& bounds,
                          const std::string& label, const std::string& x_name,
                          const std::string& y_name, std::size_t most) {
  std::vector<const HoverPoint*> inside;
  for (const HoverPoint& p : points) {
    if (svg::inside(p.pixel, bounds)) inside.push_back(&p);
  }
  if (inside.empty() || most == 0) return "";
  const std::size_t every = (inside.size() + most - 1) / most;
  std::string out = "<g class=\"hover\" fill=\"transparent\" pointer-events=\"all\">\n";
  for (std::size_t k = 0; k < inside.size(); k += every) {
    const HoverPoint& p = *inside[k];
    out += "<circle cx=\"" + num(p.pixel.x) + "\" cy=\"" + num(p.pixel.y) + "\" r=\"5\"><title>" +
           xml_escape((label.empty() ? "" : label + ": ") + x_name + " = " + short_number(p.x) +
                      ", " + y_name + " = " + short_number(p.y) +
                      (std::isfinite(p.low) && std::isfinite(p.high)
                           ? " (from " + short_number(p.low) + " to " + short_number(p.high) + ")"
                           : std::string())) +
           "</title></circle>\n";
  }
  return out + "</g>\n";
}

// A × centred at p.
std::string cross_mark(const svg::Point& p, const std::string& color) {
  const std::string d = std::string("M") + num(p.x - 4) + " " + num(p.y - 4) + "l8 8M" + num(p.x - 4) + " " +
                        num(p.y + 4) + "l8 -8";
  return svg::path(d, "stroke=\"" + color + "\" stroke-width=\"2.2\" fill=\"none\"");
}

// An arrow at p pointing up (or down) out of the frame: a value beyond the axis.
std::string edge_arrow(const svg::Point& p, bool up, const std::string& color) {
  const double tip = up ? -5 : 5;
  return svg::path(std::string("M") + num(p.x) + " " + num(p.y - tip) + "V" + num(p.y + tip) +
                       "M" + num(p.x - 4) + " " + num(p.y + tip - (up ? -4 : 4)) + "L" +
                       num(p.x) + " " + num(p.y + tip) + "L" + num(p.x + 4) + " " +
                       num(p.y + tip - (up ? -4 : 4)),
                   "stroke=\"" + color + "\" stroke-width=\"2\" fill=\"none\"");
}

// A ▼ with its tip at p.
std::string down_triangle(const svg::Point& p, const std::string& color) {
  return svg::path(std::string("M") + num(p.x - 4.5) + " " + num(p.y - 8) + "h9L" + num(p.x) + " " + num(p.y) +
                       "Z",
                   "fill=\"" + color + "\" stroke=\"white\" stroke-width=\"0.8\"");
}

// A ◆ at p, outlined in white.
std::string diamond_mark(const svg::Point& p, const std::string& color) {
  return svg::path(marker_path(3, p, 9),
                   "fill=\"" + color + "\" stroke=\"white\" stroke-width=\"1.2\"");
}

}  // namespace physgrad::plot
