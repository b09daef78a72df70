#include "physgrad/report/plot_legend.hpp"

#include <algorithm>
#include <cmath>

#include "physgrad/report/plot_geometry.hpp"

namespace physgrad::plot {

using svg::num;

Occupancy::Occupancy(const svg::Box& box, double cell)
    : box_(box),
      cell_(cell),
      nx_(std::max(1, static_cast<int>(std::ceil(box.width() / cell)))),
      ny_(std::max(1, static_cast<int>(std::ceil(box.height() / cell)))),
      used_(static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_), 0) {}

void Occupancy::mark(const svg::Point& p) {
  if (!svg::inside(p, box_)) return;
  const int i = std::min(nx_ - 1, static_cast<int>((p.x - box_.left) / cell_));
  const int j = std::min(ny_ - 1, static_cast<int>((p.y - box_.top) / cell_));
  used_[static_cast<std::size_t>(j) * nx_ + i] = 1;
}

void Occupancy::mark_segment(svg::Point a, svg::Point b) {
  if (!clip_segment(a, b, box_)) return;
  const double length = std::hypot(b.x - a.x, b.y - a.y);
  const int samples = 1 + static_cast<int>(length / (0.5 * cell_));
  for (int k = 0; k <= samples; ++k) {
    const double t = static_cast<double>(k) / samples;
    mark({a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)});
  }
}

void Occupancy::mark_polyline(const svg::Polyline& line) {
  if (line.size() == 1) mark(line[0]);
  for (std::size_t k = 1; k < line.size(); ++k) mark_segment(line[k - 1], line[k]);
}

void Occupancy::mark_box(const svg::Box& b) {
  for (double y = std::max(b.top, box_.top); y <= std::min(b.bottom, box_.bottom); y += cell_) {
    for (double x = std::max(b.left, box_.left); x <= std::min(b.right, box_.right); x += cell_) {
      mark({x, y});
    }
  }
}

int Occupancy::count(const svg::Box& b) const {
  const auto cell_index = [this](double v, double origin, int n) {
    return std::clamp(static_cast<int>(std::floor((v - origin) / cell_)), 0, n - 1);
  };
  const int i0 = cell_index(b.left, box_.left, nx_), i1 = cell_index(b.right, box_.left, nx_);
  const int j0 = cell_index(b.top, box_.top, ny_), j1 = cell_index(b.bottom, box_.top, ny_);
  int n = 0;
  for (int j = j0; j <= j1; ++j) {
    for (int i = i0; i <= i1; ++i) n += used_[static_cast<std::size_t>(j) * nx_ + i];
  }
  return n;
}

namespace {

constexpr double kRow = 17, kSwatch = 24, kPad = 8;

// One entry's swatch and label with the swatch's left end at x and its centre line at y.
std::string entry_svg(const LegendEntry& e, double x, double y) {
  const std::string color = xml_escape(e.color);
  std::string out;
  if (e.band) {
    out += svg::rect({x, y - 5, x + kSwatch, y + 5},
                     "fill=\"" + color + "\" fill-opacity=\"0.18\" stroke=\"none\"");
  }
  if (e.line) {
    out += svg::path(std::string("M") + num(x) + " " + num(y) + "h" + num(kSwatch),
                     "stroke=\"" + color + "\" stroke-width=\"2\"" +
                         (e.dashes.empty() ? "" : " stroke-dasharray=\"" + e.dashes + "\""));
  }
  if (e.dot || !e.line) {
    out += "<circle cx=\"" + num(x + kSwatch / 2) + "\" cy=\"" + num(y) + "\" r=\"" +
           (e.line ? "2.5" : "4") + "\" fill=\"" + color + "\"/>\n";
  }
  return out + svg::text(x + kSwatch + 6, y + 4, e.label, "fill=\"#222\"");
}

double entry_width(const LegendEntry& e) { return kSwatch + 6 + svg::text_width(e.label) + 4; }

}  // namespace

double legend_entry_width(const std::vector<LegendEntry>& entries) {
  double widest = 0;
  for (const LegendEntry& e : entries) {
    if (!e.label.empty()) widest = std::max(widest, entry_width(e));
  }
  return widest + 2 * kPad;
}

LegendLayout legend(const std::vector<LegendEntry>& entries, const svg::Box& box,
                    const Occupancy& occupied, double below_top, int width, bool inside) {
  std::vector<const LegendEntry*> shown;
  double widest = 0;
  for (const LegendEntry& e : entries) {
    if (e.label.empty()) continue;
    shown.push_back(&e);
    widest = std::max(widest, entry_width(e));
  }
  if (shown.empty()) return {};
  const double w = widest + 2 * kPad, h = kRow * static_cast<double>(shown.size()) + kPad;
  if (inside && w < box.width() - 12 && h < box.height() - 12) {
    const double l = box.left + 6, r = box.right - 6 - w, cx = (box.left + box.right - w) / 2;
    const double t = box.top + 6, b = box.bottom - 6 - h, cy = (box.top + box.bottom - h) / 2;
    for (const svg::Point& at : {svg::Point{r, t}, svg::Point{l, t}, svg::Point{r, b},
                                 svg::Point{l, b}, svg::Point{cx, t}, svg::Point{cx, b},
                                 svg::Point{r, cy}, svg::Point{l, cy}}) {
      const svg::Box frame{at.x, at.y, at.x + w, at.y + h};
      if (occupied.count(frame) > 0) continue;
      std::string out = "<g class=\"legend\">\n" +
                        svg::rect(frame, "fill=\"white\" fill-opacity=\"0.9\" stroke=\"#999\" "
                                         "rx=\"3\"");
      for (std::size_t k = 0; k < shown.size(); ++k) {
        out += entry_svg(*shown[k], at.x + kPad, at.y + kPad / 2 + kRow * (static_cast<double>(k) + 0.5));
      }
      return {out + "</g>\n", 0};
    }
  }
  // Below the plot, in columns.
  const double usable = std::max(widest, static_cast<double>(width) - 2 * kPad);
  const auto columns = std::max<std::size_t>(1, static_cast<std::size_t>(usable / widest));
  const std::size_t rows = (shown.size() + columns - 1) / columns;
  const double column_width = usable / static_cast<double>(columns);
  std::string out = "<g class=\"legend\">\n";
  for (std::size_t k = 0; k < shown.size(); ++k) {
    const double x = kPad + column_width * static_cast<double>(k % columns);
    const double y = below_top + kRow * (static_cast<double>(k / columns) + 0.5);
    out += entry_svg(*shown[k], x, y);
  }
  return {out + "</g>\n", kRow * static_cast<double>(rows) + 4};
}

}  // namespace physgrad::plot
