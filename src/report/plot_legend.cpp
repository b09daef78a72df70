#include "physgrad/report/plot_legend.hpp"

#include <algorithm>
#include <cmath>

#include "physgrad/report/plot_geometry.hpp"
#include "physgrad/report/plot_marks.hpp"

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

// The lines of a label no wider than `width` pixels, broken at spaces (a word wider than that
// stays whole).
std::vector<std::string> wrapped(const std::string& label, double width) {
  std::vector<std::string> lines(1);
  std::size_t start = 0;
  while (start <= label.size()) {
    std::size_t end = label.find(' ', start);
    if (end == std::string::npos) end = label.size();
    const std::string word = label.substr(start, end - start);
    const std::string joined = lines.back().empty() ? word : lines.back() + " " + word;
    if (!lines.back().empty() && svg::text_width(joined) > width) {
      lines.push_back(word);
    } else {
      lines.back() = joined;
    }
    start = end + 1;
  }
  return lines;
}

// One entry's swatch and label with the swatch's left end at x and its centre line at y; a label
// of several lines continues kRow below.
std::string entry_svg(const LegendEntry& e, double x, double y,
                      const std::vector<std::string>& lines) {
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
  if (e.shape > 0) {
    out += svg::path(marker_path(e.shape, {x + kSwatch / 2, y}, 7),
                     "fill=\"white\" stroke=\"" + color + "\" stroke-width=\"1.6\"");
  } else if (e.dot || !e.line || e.shape == 0) {
    out += "<circle cx=\"" + num(x + kSwatch / 2) + "\" cy=\"" + num(y) + "\" r=\"" +
           (e.line ? "2.5" : "4") + "\" fill=\"" + color + "\"/>\n";
  }
  for (std::size_t k = 0; k < lines.size(); ++k) {
    out += svg::text(x + kSwatch + 6, y + 4 + kRow * static_cast<double>(k), lines[k],
                     "fill=\"#222\"");
  }
  return out;
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
        out += entry_svg(*shown[k], at.x + kPad,
                         at.y + kPad / 2 + kRow * (static_cast<double>(k) + 0.5),
                         {shown[k]->label});
      }
      return {out + "</g>\n", 0};
    }
  }
  // Below the plot, in columns; labels wider than the figure wrapped.
  const double usable = std::max(1.0, static_cast<double>(width) - 2 * kPad);
  const double fits = std::min(widest, usable);
  const auto columns = std::max<std::size_t>(1, static_cast<std::size_t>(usable / fits));
  const double column_width = usable / static_cast<double>(columns);
  std::string out = "<g class=\"legend\">\n";
  double row = 0;  // rows of the entries placed so far, per line of columns
  for (std::size_t k = 0; k < shown.size(); k += columns) {
    std::size_t tallest = 1;
    for (std::size_t c = 0; c < columns && k + c < shown.size(); ++c) {
      const std::vector<std::string> lines =
          wrapped(shown[k + c]->label, column_width - kSwatch - 10);
      tallest = std::max(tallest, lines.size());
      out += entry_svg(*shown[k + c], kPad + column_width * static_cast<double>(c),
                       below_top + kRow * (row + 0.5), lines);
    }
    row += static_cast<double>(tallest);
  }
  return {out + "</g>\n", kRow * row + 4};
}

}  // namespace physgrad::plot
